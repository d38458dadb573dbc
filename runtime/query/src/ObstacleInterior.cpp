#include "tetrapage/runtime/query/ObstacleInterior.h"

#include <algorithm>
#include <array>
#include <vector>

#include "tetrapage/runtime/geometry/PointTetrahedron.h"
#include "tetrapage/runtime/geometry/SegmentTriangle.h"
#include "tetrapage/runtime/query/MeshWalk.h"

namespace tetrapage {
namespace {

// Barycentric weights of the bend points tried after a degenerate straight path: positive,
// unequal, far from any face, and from each other.
constexpr std::array<std::array<double, 4>, 8> kBendWeights{{{0.31, 0.23, 0.27, 0.19},
                                                             {0.17, 0.37, 0.21, 0.25},
                                                             {0.29, 0.13, 0.39, 0.19},
                                                             {0.22, 0.28, 0.11, 0.39},
                                                             {0.41, 0.19, 0.17, 0.23},
                                                             {0.14, 0.33, 0.35, 0.18},
                                                             {0.36, 0.26, 0.15, 0.23},
                                                             {0.2, 0.16, 0.31, 0.33}}};

void toggle(std::vector<std::uint32_t>& components, std::uint32_t component) {
  const auto at = std::find(components.begin(), components.end(), component);
  if (at == components.end())
    components.push_back(component);
  else
    components.erase(at);
}

// Toggles the closed components the open segment crosses; false when some closed component's triangle
// meets it other than in one interior point away from its ends (the path is degenerate).
bool count_crossings(const CollisionIndex& index, const Shard& shard,
                     const geometry::Segment& segment, std::vector<std::uint32_t>& components,
                     std::uint64_t& tests) {
  geometry::Box box;
  box.extend(segment[0]);
  box.extend(segment[1]);
  bool generic = true;
  // Triangles whose boxes meet the segment's: the exact segment test decides (an exact
  // triangle/box test first cost more than it spared).
  shard.for_each_box_candidate(
      box, [](const geometry::Box&, std::uint32_t) { return true; },
      [&](std::uint32_t local, const geometry::Triangle& triangle) {
        if (!generic) return;
        const std::uint32_t component = shard.component_id(local);
        if (!index.component_closed(component)) return;
        ++tests;
        const auto hit = geometry::classify_segment_triangle(segment, triangle);
        if (!hit) return;
        if (hit.contact == geometry::SegmentTriangleContact::interior && !hit.at_endpoint)
          toggle(components, component);
        else
          generic = false;
      });
  return generic;
}

bool on_closed_surface(const CollisionIndex& index, const Shard& shard, const geometry::Point& p,
                       std::uint64_t& tests) {
  geometry::Box box;
  box.extend(p);
  bool on = false;
  shard.for_each_candidate(box, [&](std::uint32_t local) {
    if (on || !index.component_closed(shard.component_id(local))) return;
    ++tests;
    on = geometry::segment_intersects_triangle({p, p}, shard.triangle(local));
  });
  return on;
}

// The shard from the caller's pins when it holds it (a step holds its region's), else pinned
// into `own`.
const Shard& shard_for(const CollisionIndex& index, std::uint32_t shard_id,
                       std::span<const ShardPin> held, ShardPin& own) {
  for (const ShardPin& pin : held)
    if (pin && pin.id() == shard_id) return *pin;
  own = index.cache().acquire(shard_id);
  return *own;
}

// The answer of a decided point from the closed components holding it.
ObstacleQuery decided(ObstacleQuery answer, const std::vector<std::uint32_t>& components) {
  if (components.empty()) {
    answer.containment = ObstacleContainment::outside;
  } else {
    answer.containment = ObstacleContainment::inside;
    answer.component = *std::min_element(components.begin(), components.end());
  }
  return answer;
}

// From the tet's reference point (the tet holds p); `components` receives the closed components holding
// p when the answer is inside or outside.
ObstacleQuery from_reference(const CollisionIndex& index, std::uint32_t tet,
                             const geometry::Point& p, std::vector<std::uint32_t>& components,
                             std::span<const ShardPin> held) {
  ObstacleQuery answer;
  answer.tet = tet;
  if (!index.interior_decided(tet)) return answer;
  const TetMesh& mesh = index.mesh();
  const auto stored = index.interior_components(tet);
  components.assign(stored.begin(), stored.end());
  const auto finish = [&] { return decided(answer, components); };
  const std::uint32_t shard_id = index.shard_of_tet(tet);
  const geometry::Point& reference = index.reference_point(tet);
  geometry::Box reach;
  reach.extend(reference);
  reach.extend(p);
  if (shard_id == TetMesh::no_neighbour ||
      !geometry::boxes_overlap(reach, index.shard_bounds(shard_id))) {
    answer.paths_tried = 1;
    return finish();  // no stored triangle near the segment: nothing to cross
  }
  ShardPin own;
  const Shard& shard = shard_for(index, shard_id, held, own);
  ++answer.paths_tried;
  if (count_crossings(index, shard, {reference, p}, components, answer.triangle_tests)) return finish();
  if (on_closed_surface(index, shard, p, answer.triangle_tests)) {
    answer.containment = ObstacleContainment::on_surface;
    return answer;
  }
  const auto corners = mesh.corners(tet);
  for (const auto& w : kBendWeights) {
    geometry::Point bend{};
    for (int a = 0; a < 3; ++a)
      bend[a] =
          w[0] * corners[0][a] + w[1] * corners[1][a] + w[2] * corners[2][a] + w[3] * corners[3][a];
    // Rounding may move the bend point: it must stay strictly inside for the path to stay in.
    if (geometry::locate_in_tetrahedron(bend, corners).position !=
        geometry::TetrahedronPosition::inside)
      continue;
    components.assign(stored.begin(), stored.end());
    ++answer.paths_tried;
    if (count_crossings(index, shard, {reference, bend}, components, answer.triangle_tests) &&
        count_crossings(index, shard, {bend, p}, components, answer.triangle_tests))
      return finish();
  }
  answer.containment = ObstacleContainment::unknown;
  return answer;
}

}  // namespace

ObstacleQuery locate_in_obstacles(const CollisionIndex& index, std::uint32_t& hint_tet,
                                  const geometry::Point& p) {
  ObstacleMemo memo;
  return locate_in_obstacles(index, hint_tet, p, memo);
}

ObstacleQuery locate_in_obstacles(const CollisionIndex& index, std::uint32_t& hint_tet,
                                  const geometry::Point& p, ObstacleMemo& memo,
                                  std::span<const ShardPin> held) {
  ObstacleQuery answer;
  if (!index.has_interiors()) return answer;
  const WalkResult located = locate_point(index.mesh(), hint_tet, p);
  if (located.tet == TetMesh::no_neighbour) {
    memo.valid = false;
    answer.containment = ObstacleContainment::outside;
    return answer;
  }
  hint_tet = answer.tet = located.tet;
  if (memo.valid && memo.tet == located.tet) {
    // Both points lie in the convex tet, so the segment between them does too, and every
    // triangle it can cross is in the tet's shard.
    answer.paths_tried = 1;
    if (memo.point == p) return decided(answer, memo.components);
    const std::uint32_t shard_id = index.shard_of_tet(located.tet);
    geometry::Box reach;
    reach.extend(memo.point);
    reach.extend(p);
    if (shard_id == TetMesh::no_neighbour ||
        !geometry::boxes_overlap(reach, index.shard_bounds(shard_id))) {
      memo.point = p;
      return decided(answer, memo.components);
    }
    ShardPin own;
    if (count_crossings(index, shard_for(index, shard_id, held, own), {memo.point, p}, memo.components,
                        answer.triangle_tests)) {
      memo.point = p;
      return decided(answer, memo.components);
    }
    // A degenerate short path: decide from the reference point (which resets memo.components).
  }
  answer = from_reference(index, located.tet, p, memo.components, held);
  memo.valid = answer.containment == ObstacleContainment::inside ||
               answer.containment == ObstacleContainment::outside;
  memo.tet = located.tet;
  memo.point = p;
  return answer;
}

}  // namespace tetrapage
