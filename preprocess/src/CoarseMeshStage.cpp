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
  std::vector<Vec3> sites = sample_sites(model.sample, model.bounds, sampling);
  // A flat leaf takes two sites: at the automatic size of a large model, leaves grow until the
  // sites are about as many as one a leaf would give, so that the mesh stays near 100k tets
  // (its tables stay beside the shards at run time: 104k against 177k tets at 100M).
  const std::size_t leaf_sites = sites.size() - kBoxCornerSites;
  const bool large_model = summary.region_triangles > auto_region_triangles(0);  // past 49M
  if (options.region_triangles == 0 && large_model && leaf_sites > kAutoRegionSites) {
    const double grow = double(leaf_sites) / double(kAutoRegionSites);
    sampling.leaf_triangles = std::size_t(std::ceil(double(sampling.leaf_triangles) * grow));
    summary.region_triangles = std::size_t(std::ceil(double(summary.region_triangles) * grow));
    sites = sample_sites(model.sample, model.bounds, sampling);
  }
  summary.sites = sites.size();
  ModelCoarseMesh coarse{build_coarse_mesh(sites), enlarged_bounds(model.bounds, sampling.margin)};
  summary.regions = coarse.mesh.tet_count();
  return coarse;
}

}  // namespace tetrapage
