#include "tetrapage/tools/StabbingNumbers.h"

#include <chrono>
#include <cmath>
#include <string>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/runtime/query/MeshWalk.h"
#include "tetrapage/tools/Random.h"

namespace tetrapage {

StabbingNumbers measure_stabbing_numbers(const EmbreeMeshFaces& faces, const BoundingBox& box,
                                         const StabbingOptions& options) {
  // A flat model (a zero side) still gets segments, in its plane.
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(box.lo[k]) || !std::isfinite(box.hi[k]) || !(box.lo[k] <= box.hi[k]))
      throw InputError("stabbing numbers: the box [" + std::to_string(box.lo[k]) + ", " +
                       std::to_string(box.hi[k]) + "] on axis " + std::to_string(k) +
                       " is empty or not finite");
  if (box.lo == box.hi)
    throw InputError("stabbing numbers: the box is a single point, segments have no length");
  const auto started = std::chrono::steady_clock::now();
  const TetMesh& mesh = faces.mesh();
  Random random(options.seed);
  auto draw = [&] {
    geometry::Point p;
    for (int k = 0; k < 3; ++k) p[k] = random.uniform(box.lo[k], box.hi[k]);
    return p;
  };
  StabbingNumbers out;
  std::vector<FaceHit> hits;
  double walk_sum = 0, embree_sum = 0, tets_sum = 0, length_sum = 0;
  std::uint32_t start = 0;
  for (std::uint64_t s = 0; s < options.segments; ++s) {
    const geometry::Point a = draw(), b = draw();
    double length = 0;
    for (int k = 0; k < 3; ++k) length += (b[k] - a[k]) * (b[k] - a[k]);
    length = std::sqrt(length);
    if (length == 0) continue;  // a repeated draw: no direction to count along
    const SegmentWalk walk = walk_segment(mesh, start, a, b);
    if (!walk.tets.empty()) start = walk.tets.back();
    if (!walk.complete) ++out.incomplete_walks;
    faces.hits(a, b, hits);
    const std::uint64_t walk_tets = walk.tets.size();
    const std::uint64_t embree_tets = hits.size() + 1;
    ++out.segments;
    walk_sum += double(walk_tets) / length;
    embree_sum += double(embree_tets) / length;
    tets_sum += double(walk_tets);
    length_sum += length;
    if (walk_tets != embree_tets) {
      ++out.differing;
      if (out.differences.size() < options.max_listed)
        out.differences.push_back({a, b, walk_tets, embree_tets});
    }
  }
  if (out.segments > 0) {
    const double n = double(out.segments);
    out.walk = walk_sum / n;
    out.embree = embree_sum / n;
    out.walk_tets_per_segment = tets_sum / n;
    out.mean_length = length_sum / n;
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return out;
}

}  // namespace tetrapage
