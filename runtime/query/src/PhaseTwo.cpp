#include "PhaseTwo.h"

#include <algorithm>
#include <cmath>
#include <tuple>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/runtime/geometry/TriangleBox.h"
#include "tetrapage/runtime/geometry/TriangleDistance.h"
#include "tetrapage/runtime/geometry/TriangleTriangle.h"

namespace tetrapage {

PhaseTwo::PhaseTwo(const StepContext& step, const QueryOptions& options, bool solid_query,
                   const geometry::Box& box)
    : step_(step),
      options_(options),
      solid_query_(solid_query),
      all_(options.mode == QueryMode::all_contacts),
      may_enclose_(step.model.closed && step.index.may_hold_a_component(box)),
      box_(box),
      counters_(step.result.counters) {
  step_.solid.built = false;
  // A triangle stored in several of the step's shards is tested once: exact and double copies
  // are the input's coordinates, the same in every shard (rounded float copies each round to
  // their own shard's frame, so each is tested).
  step_.met_triangles.clear();
}

void PhaseTwo::add_contact(const Source& source, const geometry::Triangle& environment,
                           std::uint32_t object_triangle) {
  step_.result.collides = true;
  if (all_ && step_.result.contacts.size() == options_.max_contacts)
    throw InputError("the step finds more than " + std::to_string(options_.max_contacts) +
                     " contacts (the limit of one step; raise it, or narrow the clearance)");
  if (all_ || step_.result.contacts.empty()) {
    if (source.part != kNoDynamicPart) {
      step_.result.contacts.push_back(
          {Contact::kDynamicPart, source.local, object_triangle, 0, source.part});
    } else {
      const std::uint32_t component = source.shard->component_id(source.local);
      const std::uint64_t id = source.shard->triangle_id(source.local);
      step_.result.contacts.push_back(
          {step_.index.component_part(component), id, object_triangle, component, kNoDynamicPart});
      if (step_.contact_triangles.empty() || step_.contact_triangles.back().first != id)
        step_.contact_triangles.emplace_back(id, environment);
    }
  }
  if (!all_) stop_ = true;
}

void PhaseTwo::test_mesh(const Source& source, const geometry::Triangle& environment,
                         const std::array<Vec3, 3>& framed, const geometry::Box& query,
                         double grow) {
  // Object triangles that can meet the environment triangle lie within `grow` of its
  // plane, in the object's frame (its corners taken there round by less than `grow`).
  const Vec3& p0 = framed[0];
  const Vec3 u{framed[1][0] - p0[0], framed[1][1] - p0[1], framed[1][2] - p0[2]};
  const Vec3 v{framed[2][0] - p0[0], framed[2][1] - p0[1], framed[2][2] - p0[2]};
  const Vec3 n{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  const double n_size = std::fabs(n[0]) + std::fabs(n[1]) + std::fabs(n[2]);
  const double uv_size = (std::fabs(u[0]) + std::fabs(u[1]) + std::fabs(u[2])) *
                         (std::fabs(v[0]) + std::fabs(v[1]) + std::fabs(v[2]));
  auto near_plane = [&](const geometry::Box& b) {
    double lowest = 0, highest = 0, far = 0;
    for (int a = 0; a < 3; ++a) {
      const double l = b.lo[a] - p0[a], h = b.hi[a] - p0[a];
      lowest += n[a] * (n[a] > 0 ? l : h);
      highest += n[a] * (n[a] > 0 ? h : l);
      far = std::max({far, std::fabs(l), std::fabs(h)});
    }
    const double bound = 2 * grow * n_size + uv_size * far * 0x1p-40;
    return !(lowest > bound || highest < -bound);
  };
  auto test = [&](std::uint32_t object_triangle) {
    ++counters_.triangle_tests;
    if (!geometry::triangles_collide(environment, step_.object.world_triangle(object_triangle),
                                     options_.accuracy))
      return true;
    add_contact(source, environment, object_triangle);
    return all_;
  };
  // The plane prunes the object's nodes too: a large environment triangle's box holds most of
  // the object (the lion among assimp's models: 1,000 box tests a candidate without it).
  step_.model.bvh.for_each_in_box(query, near_plane, test);
}

void PhaseTwo::test_candidate(const Source& source, const geometry::Triangle& environment) {
  // The environment triangle in the object's frame (rounded: it only prunes).
  const std::array<Vec3, 3> framed{step_.object.to_object_frame(environment[0]),
                                   step_.object.to_object_frame(environment[1]),
                                   step_.object.to_object_frame(environment[2])};
  geometry::Box query;
  for (const auto& p : framed) query.extend(p);
  // The rotation back rounds by a few ulps of the coordinates' magnitude: grow far beyond.
  const Vec3& translation = step_.object.translation();
  double magnitude = step_.model.radius;
  for (const auto& p : environment)
    for (int a = 0; a < 3; ++a)
      magnitude = std::max(magnitude, std::fabs(p[a]) + std::fabs(translation[a]));
  const double grow = step_.shapes.reach() + magnitude * 0x1p-40;
  for (int a = 0; a < 3; ++a) query.lo[a] -= grow, query.hi[a] += grow;
  // In the object's own frame its box, hull and ball prune; the triangle against the world box
  // then pruned no visible share (the elk over the terrain: 28.5 candidates a near step with or
  // without it) for 5 % of the step's instructions: it is asked only of the solids.
  if (step_.shapes.own_frame()
          ? !geometry::boxes_overlap(query, step_.model.box) || step_.shapes.beyond_hull(query)
          : !geometry::triangle_intersects_box(environment, box_))
    return;
  if (step_.shapes.ball_prunes() &&
      geometry::triangle_outside_ball(framed, step_.model.ball_centre, step_.model.ball_radius + grow))
    return;
  ++counters_.candidates;
  if (solid_query_) {
    if (!step_.solid.built) step_.solid.build(options_, step_.model, step_.object, step_.coherence);
    ++counters_.triangle_tests;
    if (step_.solid.collides(environment, options_.accuracy, step_.shapes.reach()))
      add_contact(source, environment, Contact::kNoObjectTriangle);
    return;
  }
  // (A dynamic part inside the object is found by ContainmentCheck::check_dynamic.)
  if (source.shard != nullptr) note_if_enclosed(*source.shard, source.local, environment);
  test_mesh(source, environment, framed, query, grow);
}

void PhaseTwo::note_if_enclosed(const Shard& shard, std::uint32_t local,
                                const geometry::Triangle& environment) {
  // A component whose box lies in the object's may lie wholly inside it (checked once the
  // step has found no contact).
  if (!inside_counts()) return;
  const std::uint32_t component = shard.component_id(local);
  if (step_.index.component_part(component) != CollisionIndex::kNoPart &&
      geometry::box_contains(box_, step_.index.component_bounds(component)) &&
      step_.object.in_object_box(environment[0]))
    step_.containment.note_enclosed(component, environment[0]);
}

void PhaseTwo::test_shard(const Shard& shard, const DynamicObstacles* overlay) {
  // Hidden parts are skipped before anything else: not a candidate, no contact, no
  // containment (the step answers as if the index did not hold them).
  const DynamicObstacles* mask = overlay != nullptr && overlay->hides_any() ? overlay : nullptr;
  const bool same_copies =
      step_.index.stores_input_coordinates() || shard.precision() == StoredPrecision::float64;
  // The leaf the visited triangles come from (each leaf's triangles follow its test) lies
  // inside the object, apart from its surface.
  bool in_leaf_inside_object = false;
  auto visit = [&](std::uint32_t local, const geometry::Triangle& environment) {
    if (stop_) return;  // the shard query cannot be cut short; skip the rest
    if (mask != nullptr && mask->hidden(step_.index.component_part(shard.component_id(local)))) return;
    if (same_copies && !step_.met_triangles.insert(shard.triangle_id(local))) {
      ++counters_.repeats;
      return;
    }
    if (in_leaf_inside_object) {
      note_if_enclosed(shard, local, environment);
      return;
    }
    test_candidate(Source{&shard, local, kNoDynamicPart}, environment);
  };
  // An R-tree leaf's box holds its triangles: a leaf that reaches only the object's inside
  // holds no triangle near its surface (a grid cell's triangles reach beyond the cell).
  const bool leaves_hold_triangles = shard.kind() == ShardKind::rtree;
  const auto meets_own_box = [&](const geometry::Box& b, std::uint32_t triangles) {
    const PruningShapes::NodeReach reach = step_.shapes.reach_of(b, triangles);
    in_leaf_inside_object = leaves_hold_triangles && reach == PruningShapes::NodeReach::inside;
    counters_.leaves_inside_object += in_leaf_inside_object;
    // Such a leaf's triangles matter only as part of a component inside the object.
    if (in_leaf_inside_object && !inside_counts()) return false;
    return reach != PruningShapes::NodeReach::apart;
  };
  if (step_.shapes.prune_inner())
    shard.for_each_box_candidate_pruning_inner_nodes(box_, meets_own_box, visit);
  else
    shard.for_each_box_candidate(box_, meets_own_box, visit);
}

void PhaseTwo::test_dynamic_parts(const DynamicObstacles& overlay, PlacedObject& placed) {
  overlay.for_each_in_box(box_, [&](const DynamicObstacles::Part& part) {
    placed.rebind(*part.model);
    placed.place(part.pose);
    // The step's box in the part's frame: its corners taken there (rounded, so grown far
    // beyond the rounding: it only prunes; each triangle is decided on world coordinates).
    geometry::Box query;
    double margin = 0;
    for (int c = 0; c < 8; ++c) {
      const geometry::Point corner{c & 1 ? box_.hi[0] : box_.lo[0], c & 2 ? box_.hi[1] : box_.lo[1],
                                   c & 4 ? box_.hi[2] : box_.lo[2]};
      query.extend(placed.to_object_frame(corner));
      margin = std::max(margin, placed.frame_margin(corner));
    }
    query = geometry::inflated(query, margin);
    part.model->bvh.for_each_in_box(query, [&](std::uint32_t triangle) {
      test_candidate(Source{nullptr, triangle, part.id}, placed.world_triangle(triangle));
      return !stop_;
    });
    return !stop_;
  });
}

void PhaseTwo::finish() {
  if (!all_ || step_.result.contacts.size() <= 1) return;
  // A triangle that crosses regions is stored in each of their shards, and float copies are
  // each tested (above): report a pair once.
  auto key = [](const Contact& c) {
    return std::tie(c.dynamic_part, c.environment_triangle, c.object_triangle);
  };
  std::sort(step_.result.contacts.begin(), step_.result.contacts.end(),
            [&](const Contact& a, const Contact& b) { return key(a) < key(b); });
  step_.result.contacts.erase(std::unique(step_.result.contacts.begin(), step_.result.contacts.end()),
                         step_.result.contacts.end());
}

}  // namespace tetrapage
