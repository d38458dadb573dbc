#include "CoarseMeshStage.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "tetrapage/preprocess/CoarseMesh.h"

namespace tetrapage {

ModelCoarseMesh build_model_coarse_mesh(IngestedModel& model, const PreprocessOptions& options,
                                        PreprocessSummary& summary) {
  // The sample stands for all triangles: scale the leaf size to its share.
  const double share = double(model.sample.size()) / double(model.triangle_count);
  summary.region_triangles = options.region_triangles != 0
                                 ? options.region_triangles
                                 : auto_region_triangles(model.triangle_count);
  SamplingOptions sampling;
  sampling.leaf_triangles =
      std::max<std::size_t>(1, std::size_t(std::llround(double(summary.region_triangles) * share)));
  // Reorders the sample (the buckets' estimate takes any every-stride-th of it).
  const std::vector<Vec3> sites = sample_sites(model.sample, model.bounds, sampling);
  summary.sites = sites.size();
  ModelCoarseMesh coarse{build_coarse_mesh(sites), enlarged_bounds(model.bounds, sampling.margin)};
  summary.regions = coarse.mesh.tet_count();
  return coarse;
}

}  // namespace tetrapage
