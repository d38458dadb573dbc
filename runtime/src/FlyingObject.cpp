#include "tetrapage/runtime/FlyingObject.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <span>
#include <tuple>

#include "ConvexHull.h"
#include "tetrapage/formats/Error.h"
#include "tetrapage/runtime/MeshWalk.h"
#include "tetrapage/runtime/ObstacleInterior.h"
#include "tetrapage/runtime/geometry/Predicates.h"
#include "tetrapage/runtime/geometry/SegmentTriangle.h"
#include "tetrapage/runtime/geometry/TriangleBox.h"
#include "tetrapage/runtime/geometry/TriangleDistance.h"
#include "tetrapage/runtime/geometry/TriangleTriangle.h"

namespace tetrapage {
namespace {

using Clock = std::chrono::steady_clock;

Contact contact_with(const CollisionIndex& index, const Shard& shard, std::uint32_t local,
                     std::uint32_t object_triangle) {
  const std::uint32_t component = shard.component_id(local);
  return {index.component_part(component), shard.triangle_id(local), object_triangle, component};
}
using hull::hull_of;
using hull::Kernel;
using hull::to_point;

// Every point of `inner` lies in the interior of `outer`.
bool strictly_inside(const geometry::Box& inner, const geometry::Box& outer) {
  return inner.lo[0] > outer.lo[0] && inner.lo[1] > outer.lo[1] && inner.lo[2] > outer.lo[2] &&
         inner.hi[0] < outer.hi[0] && inner.hi[1] < outer.hi[1] && inner.hi[2] < outer.hi[2];
}

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The box's centre, clamped into the coarse mesh's box: where a walk for the box aims.
Vec3 centre_in_mesh_box(const geometry::Box& box, const CollisionIndex& index) {
  Vec3 centre = box.center();
  for (int a = 0; a < 3; ++a)
    centre[a] = std::clamp(centre[a], index.mesh_bounds().lo[a], index.mesh_bounds().hi[a]);
  return centre;
}

// How far the placement (apply_pose) may move a vertex, relative to the object's radius plus
// the translation's magnitude, taken far beyond the few ulps it really moves: a vertex deeper
// inside the object's hull than this cannot reach the hull of the placed hull vertices.
constexpr double kPlacementReach = 0x1p-36;

}  // namespace

/// The solid standing for the object in one step: a box, or a convex hull as triangles (CGAL's
/// hull, outward, coplanar facets triangulated) with the orient3d sign of outside points.
struct FlyingObject::Solid {
  enum class Kind : std::uint8_t { box, hull } kind = Kind::box;
  bool built = false;
  geometry::Box box;  ///< box: the solid; hull: the hull's box
  std::vector<geometry::Triangle> faces;
  std::vector<geometry::Box> face_boxes;
  /// zero for a flat hull (no inside: only its faces count)
  geometry::Sign outside = geometry::Sign::zero;
  // Scratch of the hull construction.
  std::vector<Kernel::Point_3> points, hull_points;
  std::vector<std::array<std::size_t, 3>> hull_faces;
};

FlyingObject::FlyingObject(std::shared_ptr<const CollisionIndex> index, TriangleSoup object)
    : FlyingObject(std::move(index), std::make_shared<const ObjectModel>(std::move(object))) {}

FlyingObject::FlyingObject(std::shared_ptr<const CollisionIndex> index,
                           std::shared_ptr<const ObjectModel> model)
    : index_(std::move(index)), model_(std::move(model)) {
  if (!index_) throw InputError("a flying object needs an index");
  if (!model_) throw InputError("a flying object needs an object model");
  world_.resize(model_->mesh.vertices.size());
  world_step_.assign(model_->mesh.vertices.size(), ~std::uint64_t{0});
}

void FlyingObject::build_solid(const QueryOptions& options, Solid& solid) {
  solid.built = true;
  solid.faces.clear();
  solid.face_boxes.clear();
  solid.outside = geometry::Sign::zero;
  const bool swept = options.motion == Motion::swept && previous_valid_;
  if (options.shape == ObjectShape::box) {
    solid.kind = Solid::Kind::box;
    solid.box = current_box_;
    if (swept) solid.box.extend(previous_box_);
    return;
  }
  solid.kind = Solid::Kind::hull;
  const ObjectModel::HullCandidates& candidates = model_->hull_candidates();
  // The hull candidates at each pose: the object's hull vertices and the vertices within the
  // placement's reach of its surface.
  auto magnitude = [&](const Vec3& t) {
    return model_->radius + std::max({std::fabs(t[0]), std::fabs(t[1]), std::fabs(t[2])});
  };
  double reach = magnitude(translation_);
  if (swept) reach = std::max(reach, magnitude(previous_translation_));
  reach *= kPlacementReach;
  solid.points.clear();
  auto add_pose = [&](bool current) {
    auto add = [&](std::uint32_t v) {
      const Vec3 p =
          current ? world_vertex(v)
                  : apply_pose(previous_rotation_, previous_translation_, model_->mesh.vertices[v]);
      solid.points.emplace_back(p[0], p[1], p[2]);
    };
    for (const auto v : candidates.on_hull) add(v);
    for (const auto& [depth, v] : candidates.near_hull) {
      if (depth > reach) break;
      add(v);
    }
  };
  add_pose(true);
  if (swept) add_pose(false);
  std::sort(solid.points.begin(), solid.points.end());
  solid.points.erase(std::unique(solid.points.begin(), solid.points.end()), solid.points.end());
  solid.hull_points.clear();
  solid.hull_faces.clear();
  if (solid.points.size() >= 4) hull_of(solid.points, solid.hull_points, solid.hull_faces);
  for (const auto& f : solid.hull_faces)
    solid.faces.push_back({to_point(solid.hull_points[f[0]]), to_point(solid.hull_points[f[1]]),
                           to_point(solid.hull_points[f[2]])});
  if (solid.faces.empty()) {
    // Fewer than four points, or no hull: the placed triangles stand for themselves.
    for (std::uint32_t t = 0; t < model_->mesh.triangle_count(); ++t)
      solid.faces.push_back(world_triangle(t));
  } else {
    // CGAL orients every facet the same way: the first vertex off facet 0 names the inside.
    const auto& f = solid.faces[0];
    for (const auto& p : solid.hull_points) {
      const geometry::Sign s = geometry::orient3d(f[0], f[1], f[2], to_point(p));
      if (s != geometry::Sign::zero) {
        solid.outside = -s;
        break;
      }
    }
  }
  solid.box = {};
  for (const auto& face : solid.faces) {
    solid.face_boxes.push_back(geometry::box_of(face));
    solid.box.extend(solid.face_boxes.back());
  }
}

bool FlyingObject::solid_collides(const Solid& solid, const geometry::Triangle& environment,
                                  const geometry::Accuracy& accuracy, double reach) {
  if (solid.kind == Solid::Kind::box)
    return geometry::triangle_collides_with_box(environment, solid.box, accuracy);
  geometry::Box near = geometry::box_of(environment);
  if (reach > 0) near = geometry::inflated(near, reach);
  if (!geometry::boxes_overlap(near, solid.box)) return false;
  for (std::size_t i = 0; i < solid.faces.size(); ++i)
    if (geometry::boxes_overlap(near, solid.face_boxes[i]) &&
        geometry::triangles_collide(environment, solid.faces[i], accuracy))
      return true;
  // No surface contact: the triangle lies wholly inside or wholly outside; one vertex decides,
  // exactly whatever the accuracy.
  if (solid.outside == geometry::Sign::zero || !geometry::box_contains(solid.box, environment[0]))
    return false;
  for (const auto& f : solid.faces)
    if (geometry::orient3d(f[0], f[1], f[2], environment[0]) == solid.outside) return false;
  return true;
}

FlyingObject::~FlyingObject() = default;
FlyingObject::FlyingObject(FlyingObject&&) noexcept = default;
FlyingObject& FlyingObject::operator=(FlyingObject&&) noexcept = default;

void FlyingObject::place(const Pose& pose) {
  const double n = pose.rotation[0] * pose.rotation[0] + pose.rotation[1] * pose.rotation[1] +
                   pose.rotation[2] * pose.rotation[2] + pose.rotation[3] * pose.rotation[3];
  if (!(std::isfinite(pose.translation[0]) && std::isfinite(pose.translation[1]) &&
        std::isfinite(pose.translation[2])) ||
      !std::isfinite(n) || std::fabs(n - 1) > 1e-6) {
    char text[200];
    std::snprintf(text, sizeof text,
                  "invalid pose: translation (%g, %g, %g), quaternion (%g, %g, %g, %g)",
                  pose.translation[0], pose.translation[1], pose.translation[2], pose.rotation[0],
                  pose.rotation[1], pose.rotation[2], pose.rotation[3]);
    throw InputError(text);
  }
  // Object coordinates are within the same bound (ObjectModel): R x + t then stays finite.
  for (int a = 0; a < 3; ++a)
    if (std::fabs(pose.translation[a]) > kMaxCoordinateMagnitude) {
      char text[200];
      std::snprintf(
          text, sizeof text,
          "invalid pose: translation %c = %g is beyond %g in magnitude: placing the object "
          "there would overflow",
          "xyz"[a], pose.translation[a], kMaxCoordinateMagnitude);
      throw InputError(text);
    }
  // rotation_matrix normalises a q off unit norm: every prune here assumes an orthogonal
  // matrix up to rounding.
  rotation_ = rotation_matrix(pose.rotation);
  translation_ = pose.translation;
  ++step_;
}

const Vec3& FlyingObject::world_vertex(std::uint32_t v) {
  if (world_step_[v] != step_) {
    world_[v] = apply_pose(rotation_, translation_, model_->mesh.vertices[v]);
    world_step_[v] = step_;
  }
  return world_[v];
}

geometry::Triangle FlyingObject::world_triangle(std::uint32_t t) {
  const auto& c = model_->mesh.triangles[t];
  return {world_vertex(c[0]), world_vertex(c[1]), world_vertex(c[2])};
}

geometry::Box FlyingObject::world_box(const Pose& pose) {
  place(pose);
  geometry::Box box;
  if (model_->hull_offsets.empty()) {
    for (const auto v : model_->hull_vertices) box.extend(world_vertex(v));
  } else {
    // Per axis and side, climb from the last extreme to a vertex no neighbour beats: on a
    // convex polytope a local extreme of a linear function is the global one. Only the
    // axis's coordinate is computed (apply_pose's row, the same operations).
    for (int k = 0; k < 6; ++k) {
      const int axis = k / 2;
      const double sign = k % 2 == 0 ? -1.0 : 1.0;
      const double r0 = rotation_[3 * axis], r1 = rotation_[3 * axis + 1],
                   r2 = rotation_[3 * axis + 2];
      const auto coordinate = [&](std::uint32_t hull_vertex) {
        const Vec3& x = model_->mesh.vertices[model_->hull_vertices[hull_vertex]];
        return r0 * x[0] + r1 * x[1] + r2 * x[2] + translation_[axis];
      };
      std::uint32_t at = extreme_[k];
      double best = sign * coordinate(at);
      for (bool moved = true; moved;) {
        moved = false;
        // The neighbours of the vertex the pass started from: `at` moves during the pass.
        const std::uint32_t from = at;
        for (std::uint32_t i = model_->hull_offsets[from]; i < model_->hull_offsets[from + 1];
             ++i) {
          const std::uint32_t next = model_->hull_neighbours[i];
          const double value = sign * coordinate(next);
          if (value > best) best = value, at = next, moved = true;
        }
      }
      extreme_[k] = at;
      (k % 2 == 0 ? box.lo[axis] : box.hi[axis]) = sign * best;
    }
  }
  // The placement rounds each coordinate; rounded values can make a near-tie climb stop one
  // vertex short. Grow the box far beyond those roundings (it only prunes).
  const double magnitude =
      model_->radius + std::max({std::fabs(translation_[0]), std::fabs(translation_[1]),
                                 std::fabs(translation_[2])});
  const double margin = magnitude * 0x1p-40;
  for (int a = 0; a < 3; ++a) box.lo[a] -= margin, box.hi[a] += margin;
  return box;
}

bool FlyingObject::search(const geometry::Box& box, StepCounters& counters) {
  const CollisionIndex& index = *index_;
  const TetMesh& mesh = index.mesh();
  counters.searched = true;
  auto start = Clock::now();
  // Grow by half the box's extent each side: a billiard object then crosses the margin in
  // about ten steps of 0.005 for a 0.05 object, and re-searches that often.
  const double grow = 0.5 * geometry::extent(box);
  geometry::Box region = box;
  for (int a = 0; a < 3; ++a) region.lo[a] -= grow, region.hi[a] += grow;
  const WalkResult located = locate_point(mesh, last_tet_, centre_in_mesh_box(box, index));
  counters.tets_crossed = located.tets_crossed;
  counters.locate_seconds += seconds_since(start);  // after the box time of query()
  if (located.tet == TetMesh::no_neighbour) return false;
  last_tet_ = located.tet;

  start = Clock::now();
  // Bounding boxes are enough here: the region only has to cover the steps' boxes, and each
  // step skips the shards whose stored bounds miss its box.
  const BoxSearchResult found =
      tets_near_box(mesh, index.tet_filter(), located.tet, region, search_);
  counters.tets_visited = found.tets_visited;
  counters.tets_overlapping = std::uint32_t(found.tets.size());
  // The last region's pins, for the shards the new region keeps: releasing them and acquiring
  // them again took the cache's lock twice each.
  previous_shards_.swap(shards_);
  previous_pins_.swap(pins_);
  shards_.clear();
  shard_reach_.clear();
  shard_tet_.clear();
  for (const std::uint32_t tet : found.tets) {
    const std::uint32_t shard = index.shard_of_tet(tet);
    if (shard == TetMesh::no_neighbour) continue;
    // A shard's triangles that meet a step's box there meet it inside the shard's tet, or
    // inside another tet of the region (whose shard holds them too): a step needs the shard
    // only when its box meets both the tet's box and the stored bounds.
    const geometry::Box& tet_box = index.tet_filter().bounds(tet);
    const geometry::Box& stored = index.shard_bounds(shard);
    geometry::Box reach;
    for (int a = 0; a < 3; ++a) {
      reach.lo[a] = std::max(tet_box.lo[a], stored.lo[a]);
      reach.hi[a] = std::min(tet_box.hi[a], stored.hi[a]);
    }
    if (!geometry::boxes_overlap(region, reach)) continue;
    shards_.push_back(shard);
    shard_reach_.push_back(reach);
    shard_tet_.push_back(tet);
  }
  counters.search_seconds = seconds_since(start);

  // Pins of the region's shards are taken when a step first needs them, and kept while the
  // object stays in the region (unless the region outweighs an eighth of the budget, which
  // other objects share: then each step pins one shard at a time).
  pins_.clear();
  std::uint64_t region_bytes = 0;
  for (const std::uint32_t shard : shards_) region_bytes += index.shard_bytes(shard);
  keep_pins_ = region_bytes <= index.options().memory_budget_bytes / 8;
  if (keep_pins_) {
    pins_.resize(shards_.size());
    for (std::size_t k = 0; k < previous_pins_.size(); ++k) {
      if (!previous_pins_[k]) continue;
      const auto kept = std::find(shards_.begin(), shards_.end(), previous_shards_[k]);
      if (kept != shards_.end())
        pins_[std::size_t(kept - shards_.begin())] = std::move(previous_pins_[k]);
    }
  }
  previous_pins_.clear();  // the rest are released

  if (index.options().prefetch) {
    // The region's shards that the box does not meet yet but would within four more steps of
    // its last motion: load them in the background now rather than synchronously then. (All
    // the region's shards were loaded two to three times over for those the flights then
    // used, and the useless loads evicted useful ones: docs/history/benchmarks-to-2026-11-26.md.)
    constexpr double kHintSteps = 4;
    geometry::Box ahead = region;
    if (previous_valid_) {
      ahead = box;
      for (int a = 0; a < 3; ++a) {
        const double d = kHintSteps * (current_box_.center()[a] - previous_box_.center()[a]);
        (d < 0 ? ahead.lo[a] : ahead.hi[a]) += d;
      }
    }
    hints_.clear();
    for (std::size_t k = 0; k < shards_.size(); ++k)
      if (!geometry::boxes_overlap(box, shard_reach_[k]) &&
          geometry::boxes_overlap(ahead, shard_reach_[k]) &&
          index.tet_filter().planes_may_meet(shard_tet_[k], ahead) &&
          !index.cache().contains(shards_[k]))
        hints_.push_back(shards_[k]);
    if (!hints_.empty()) index.cache().prefetch(hints_);
  }
  if (index.options().prefetch && index.options().prefetch_ahead && searched_valid_) {
    // The next region, if the motion since the last search goes on.
    geometry::Box next = region;
    const Vec3 now = box.center();
    for (int a = 0; a < 3; ++a) {
      const double d = now[a] - searched_centre_[a];
      next.lo[a] += d, next.hi[a] += d;
    }
    prefetch_ahead(next, located.tet);
  }
  searched_box_ = region;
  searched_centre_ = box.center();
  searched_valid_ = true;
  return true;
}

void FlyingObject::prefetch_ahead(const geometry::Box& next_region, std::uint32_t from_tet) {
  const CollisionIndex& index = *index_;
  const TetMesh& mesh = index.mesh();
  const WalkResult ahead = locate_point(mesh, from_tet, centre_in_mesh_box(next_region, index));
  if (ahead.tet == TetMesh::no_neighbour ||
      !geometry::boxes_overlap(next_region, mesh.bounds(ahead.tet)))
    return;
  hints_.clear();
  for (const std::uint32_t tet :
       tets_near_box(mesh, index.tet_filter(), ahead.tet, next_region, prefetch_search_).tets) {
    const std::uint32_t shard = index.shard_of_tet(tet);
    if (shard != TetMesh::no_neighbour &&
        geometry::boxes_overlap(next_region, index.shard_bounds(shard)) &&
        !index.cache().contains(shard))
      hints_.push_back(shard);
  }
  if (!hints_.empty()) index.cache().prefetch(hints_);
}

void FlyingObject::release_region() {
  // Outside the model nothing needs the region's shards: give their budget back.
  pins_.clear();
  shards_.clear();
  shard_reach_.clear();
  shard_tet_.clear();
  searched_valid_ = false;
}

void FlyingObject::query(const Pose& pose, const QueryOptions& options, QueryResult& result) {
  result.collides = false;
  result.containment = Containment::none;
  result.containing_part = 0;
  result.containing_component = 0;
  result.contacts.clear();
  enclosed_.clear();
  result.outside_model = false;
  result.counters = {};
  StepCounters& counters = result.counters;
  const CollisionIndex& index = *index_;

  // A step that may end inside the free box reads no clock before it knows (two reads were a
  // tenth of such a step's time); its box's time is then not counted.
  const bool time_box = !free_box_valid_;
  Clock::time_point start;
  if (time_box) start = Clock::now();
  geometry::Box box = world_box(pose);
  current_box_ = box;
  // Whatever way this query leaves, its pose is the next one's previous pose (swept motion).
  struct RememberPose {
    FlyingObject& object;
    ~RememberPose() {
      object.previous_valid_ = true;
      object.previous_rotation_ = object.rotation_;
      object.previous_translation_ = object.translation_;
      object.previous_box_ = object.current_box_;
    }
  } remember{*this};
  // The object as a solid (hull or box, or swept between the poses), or as its mesh.
  const bool swept = options.motion == Motion::swept && previous_valid_;
  const bool solid_query = options.shape != ObjectShape::mesh || swept;
  // The phase I box covers both poses of a swept step.
  if (swept) box.extend(previous_box_);
  // Environment triangles within the accuracy's reach of the object count: grow the box.
  const double reach =
      geometry::collision_margin(options.accuracy, geometry::extent(box), geometry::extent(box));
  if (solid_query)
    box = reach > 0 ? geometry::inflated(box, reach) : box;  // covers the solid box's own growth
  else if (reach > 0)
    for (int a = 0; a < 3; ++a) box.lo[a] -= reach, box.hi[a] += reach;
  result.world_box = box;
  if (free_box_valid_ && strictly_inside(box, free_box_)) {
    // (The free box lies in the mesh's box: the object is not outside the model.)
    counters.in_free_box = true;
    return;
  }
  // The clock's reads were 6 % of the time of a flight of free steps (perf): one reading ends a
  // phase and starts the next.
  Clock::time_point phase_start = Clock::now();
  if (time_box)
    counters.locate_seconds = std::chrono::duration<double>(phase_start - start).count();
  if (!geometry::boxes_overlap(box, index.mesh_bounds())) {
    result.outside_model = true;
    release_region();
    return;
  }
  const bool inside_region = searched_valid_ && box.lo[0] >= searched_box_.lo[0] &&
                             box.lo[1] >= searched_box_.lo[1] && box.lo[2] >= searched_box_.lo[2] &&
                             box.hi[0] <= searched_box_.hi[0] && box.hi[1] <= searched_box_.hi[1] &&
                             box.hi[2] <= searched_box_.hi[2];
  if (!inside_region) {
    if (!search(box, counters)) {
      // A centre outside the convex mesh: the box meets only the model's empty margin.
      result.outside_model = true;
      release_region();
      return;
    }
    phase_start = Clock::now();
  }

  // Most steps far from obstacles find a box around them that holds no triangle, and then
  // need no phase I; the next steps inside it need nothing else.
  if (step_in_new_free_box(box, result)) return;

  // Phase I and II over the region's shards whose bounds meet the box.
  const bool all = options.mode == QueryMode::all_contacts;
  bool stop = false;
  // The object's own box prunes in its frame while the question is about the current pose's
  // object or its hull (both inside that box), not for its world box or a swept solid.
  const bool own_frame = !solid_query || (options.shape == ObjectShape::hull && !swept);
  if (!solid_) solid_ = std::make_unique<Solid>();
  solid_->built = false;
  // The object's own box (grown by the reach), to prune R-tree nodes and triangles in its
  // frame: for a rotated object it is much tighter than the world box.
  geometry::Point own_centre, own_half;
  for (int a = 0; a < 3; ++a) {
    own_centre[a] = 0.5 * (model_->box.lo[a] + model_->box.hi[a]);
    own_half[a] = 0.5 * (model_->box.hi[a] - model_->box.lo[a]) + reach;
  }
  const double translation_magnitude = std::max(
      {std::fabs(translation_[0]), std::fabs(translation_[1]), std::fabs(translation_[2])});
  // Does a world box meet the object's own box? Its centre taken to the object's frame and
  // its half extents through |R| (separating axes of the object's frame); the roundings are
  // covered by a margin far beyond them. Conservative: it only prunes.
  // For the mesh, a node must also come near the object's surface (its BVH) or lie inside it:
  // a node whose box meets no object triangle's box lies wholly inside or wholly outside the
  // object, and one point of it tells which.
  const bool near_surface_only = own_frame && !solid_query;
  // The surface test pays off on leaves and cells that hold a few triangles and are small
  // beside the object (measured on the 1M and 10M scenes with 500 to 15,000 triangles): a
  // larger box nearly always meets the surface anyway.
  constexpr std::uint32_t kSurfaceTestTriangles = 4;
  const double surface_test_extent =
      0.1 * std::max({model_->box.hi[0] - model_->box.lo[0], model_->box.hi[1] - model_->box.lo[1],
                      model_->box.hi[2] - model_->box.lo[2]});
  // A box in the object's frame wholly beyond one of the hull's planes misses the object and
  // its hull (the margin covers the planes' rounding, far beyond it).
  const double plane_margin = model_->radius * 0x1p-30;
  using Plane = std::pair<Vec3, double>;  // n.x <= offset holds the object
  auto box_beyond_planes = [](std::span<const Plane> planes, double margin,
                              const geometry::Box& b) {
    for (const auto& [n, offset] : planes) {
      double lowest = 0;
      for (int a = 0; a < 3; ++a) lowest += n[a] * (n[a] > 0 ? b.lo[a] : b.hi[a]);
      if (lowest > offset + margin) return true;
    }
    return false;
  };
  auto beyond_hull = [&](const geometry::Box& b) {
    return box_beyond_planes(model_->hull_planes, plane_margin, b);
  };
  // For a round object, a box in its frame wholly outside the ball that holds it misses it
  // and its hull (the box is grown by the reach and margins already; the ball by far more
  // than the roundings of this test).
  const bool ball_prunes = own_frame && model_->ball_prunes;
  const double ball_reach = model_->ball_radius * (1 + 0x1p-30);
  auto box_outside_ball = [&](const geometry::Box& b, const Vec3& centre, double radius) {
    double squared = 0;
    for (int a = 0; a < 3; ++a) {
      const double gap = std::max({b.lo[a] - centre[a], centre[a] - b.hi[a], 0.0});
      squared += gap * gap;
    }
    return squared > radius * radius;
  };
  auto outside_ball = [&](const geometry::Box& b) {
    return ball_prunes && box_outside_ball(b, model_->ball_centre, ball_reach);
  };
  // The ball placed in the world (its centre by apply_pose's arithmetic): a world box that
  // misses it misses the object, with no turn into the object's frame. Its radius is grown by
  // the reach and far beyond the placement's rounding.
  Vec3 world_ball_centre{};
  double world_ball_reach = 0;
  if (ball_prunes) {
    world_ball_centre = apply_pose(rotation_, translation_, model_->ball_centre);
    world_ball_reach = ball_reach + reach +
                       (model_->radius + model_->ball_radius + translation_magnitude) * 0x1p-40;
  }
  auto world_box_outside_ball = [&](const geometry::Box& b) {
    return ball_prunes && box_outside_ball(b, world_ball_centre, world_ball_reach);
  };
  // The hull's planes placed in the world, likewise: a world box wholly beyond one misses the
  // object (the tetrahedron's world box is up to five times its volume). Offsets grown by the
  // reach, and by far more than the placement's and this test's roundings over any box of the
  // model.
  world_planes_.clear();
  if (own_frame && !model_->hull_planes.empty()) {
    world_planes_.resize(model_->hull_planes.size());
    const geometry::Box& model_box = index.mesh_bounds();
    const double magnitude = model_->radius + translation_magnitude +
                             std::max({std::fabs(model_box.lo[0]), std::fabs(model_box.lo[1]),
                                       std::fabs(model_box.lo[2]), std::fabs(model_box.hi[0]),
                                       std::fabs(model_box.hi[1]), std::fabs(model_box.hi[2])});
    for (std::size_t k = 0; k < model_->hull_planes.size(); ++k) {
      const auto& [n, offset] = model_->hull_planes[k];
      auto& [w, world_offset] = world_planes_[k];
      for (int a = 0; a < 3; ++a)
        w[a] = rotation_[3 * a] * n[0] + rotation_[3 * a + 1] * n[1] + rotation_[3 * a + 2] * n[2];
      world_offset = offset + w[0] * translation_[0] + w[1] * translation_[1] +
                     w[2] * translation_[2] + reach + plane_margin + magnitude * 0x1p-40;
    }
  }
  // Either shape placed in the world: a world box it rules out misses the object.
  auto world_shapes_miss = [&](const geometry::Box& b) {
    return world_box_outside_ball(b) || box_beyond_planes(world_planes_, 0.0, b);
  };
  auto meets_own_box = [&](const geometry::Box& b, std::uint32_t triangles) {
    if (!own_frame) return true;
    if (world_shapes_miss(b)) return false;
    Vec3 c, h;
    for (int a = 0; a < 3; ++a)
      c[a] = 0.5 * (b.lo[a] + b.hi[a]) - translation_[a], h[a] = 0.5 * (b.hi[a] - b.lo[a]);
    const double margin = (std::max({std::fabs(b.lo[0]), std::fabs(b.lo[1]), std::fabs(b.lo[2]),
                                     std::fabs(b.hi[0]), std::fabs(b.hi[1]), std::fabs(b.hi[2])}) +
                           translation_magnitude + model_->radius) *
                          0x1p-40;
    geometry::Box in_frame;  // the node's box in the object's frame, grown by reach and margin
    for (int a = 0; a < 3; ++a) {
      const double x = rotation_[a] * c[0] + rotation_[3 + a] * c[1] + rotation_[6 + a] * c[2];
      const double e = std::fabs(rotation_[a]) * h[0] + std::fabs(rotation_[3 + a]) * h[1] +
                       std::fabs(rotation_[6 + a]) * h[2];
      if (std::fabs(x - own_centre[a]) > e + own_half[a] + margin) return false;
      in_frame.lo[a] = x - e - reach - margin;
      in_frame.hi[a] = x + e + reach + margin;
    }
    if (beyond_hull(in_frame) || outside_ball(in_frame)) return false;
    if (!near_surface_only || triangles < kSurfaceTestTriangles ||
        std::max({h[0], h[1], h[2]}) > surface_test_extent)
      return true;
    bool near_surface = false;
    model_->bvh.for_each_in_box(in_frame, [&](std::uint32_t) { return !(near_surface = true); });
    if (near_surface) return true;
    if (!model_->closed) return false;
    return model_->interior_grid.classify(in_frame.center(), margin) !=
           ObjectInteriorGrid::Side::outside;
  };
  // Inner R-tree nodes are asked of the object's own box too when the world box is much
  // looser than it (a turned tetrahedron's is up to five times its volume): the subtrees it
  // prunes then pay for the tests, which did not pay for a round object (measured 1 to 3
  // times: 4 triangles +7 % on the 1M and 10M scenes, the others within 1 %).
  constexpr double kLoose = 1.5;
  const double own_volume = (model_->box.hi[0] - model_->box.lo[0] + 2 * reach) *
                            (model_->box.hi[1] - model_->box.lo[1] + 2 * reach) *
                            (model_->box.hi[2] - model_->box.lo[2] + 2 * reach);
  const double world_volume =
      (box.hi[0] - box.lo[0]) * (box.hi[1] - box.lo[1]) * (box.hi[2] - box.lo[2]);
  const bool prune_inner = own_frame && world_volume > kLoose * own_volume;
  // A triangle stored in several of the step's shards is tested once: exact and double copies
  // are the input's coordinates, the same in every shard (rounded float copies each round to
  // their own shard's frame, so each is tested).
  met_triangles_.clear();
  auto test_shard = [&](const Shard& shard) {
    const bool same_copies =
        index.stores_input_coordinates() || shard.precision() == StoredPrecision::float64;
    auto visit = [&](std::uint32_t local, const geometry::Triangle& environment) {
      if (stop) return;  // the shard query cannot be cut short; skip the rest
      if (same_copies && !met_triangles_.insert(shard.triangle_id(local))) {
        ++counters.repeats;
        return;
      }
      // The environment triangle in the object's frame (rounded: it only prunes).
      const std::array<Vec3, 3> framed{to_object_frame(environment[0]),
                                       to_object_frame(environment[1]),
                                       to_object_frame(environment[2])};
      geometry::Box query;
      for (const auto& p : framed) query.extend(p);
      // The rotation back rounds by a few ulps of the coordinates' magnitude: grow far beyond.
      double magnitude = model_->radius;
      for (const auto& p : environment)
        for (int a = 0; a < 3; ++a)
          magnitude = std::max(magnitude, std::fabs(p[a]) + std::fabs(translation_[a]));
      const double grow = reach + magnitude * 0x1p-40;
      for (int a = 0; a < 3; ++a) query.lo[a] -= grow, query.hi[a] += grow;
      if ((own_frame && (!geometry::boxes_overlap(query, model_->box) || beyond_hull(query))) ||
          (ball_prunes && geometry::triangle_outside_ball(framed, model_->ball_centre,
                                                          model_->ball_radius + grow)) ||
          !geometry::triangle_intersects_box(environment, box))
        return;
      ++counters.candidates;
      if (solid_query) {
        if (!solid_->built) build_solid(options, *solid_);
        ++counters.triangle_tests;
        if (!solid_collides(*solid_, environment, options.accuracy, reach)) return;
        result.collides = true;
        if (all || result.contacts.empty())
          result.contacts.push_back(contact_with(index, shard, local, Contact::kNoObjectTriangle));
        if (!all) stop = true;
        return;
      }
      if (model_->closed && !result.collides) {
        const std::uint32_t component = shard.component_id(local);
        if (index.component_part(component) != CollisionIndex::kNoPart &&
            geometry::box_contains(box, index.component_bounds(component)) &&
            in_object_box(environment[0]))
          enclosed_.emplace_back(component, environment[0]);
      }
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
      model_->bvh.for_each_in_box(query, near_plane, [&](std::uint32_t object_triangle) {
        ++counters.triangle_tests;
        if (!geometry::triangles_collide(environment, world_triangle(object_triangle),
                                         options.accuracy))
          return true;
        result.collides = true;
        if (all || result.contacts.empty())
          result.contacts.push_back(contact_with(index, shard, local, object_triangle));
        if (!all) stop = true;
        return all;
      });
    };
    if (prune_inner)
      shard.for_each_box_candidate_pruning_inner_nodes(box, meets_own_box, visit);
    else
      shard.for_each_box_candidate(box, meets_own_box, visit);
  };
  // One clock pair around the loop (a free step is a few microseconds; a clock read per shard
  // cost a tenth of it): the tests' time is the loop's less the acquisitions'.
  const auto loop_start = phase_start;
  // Does this step need shard k? Only if its box meets the shard's reach and, before the shard
  // is pinned (a page-in is dearer than the test), the object's own box meets it in its frame:
  // a contact point, or a point of a triangle inside the object, lies in the object and in some
  // tet of the region, within that tet's reach, and that tet's shard holds the triangle.
  // Before a page-in also the tet itself, by its face planes: the coarse tets are slivers
  // whose boxes reach far beyond them.
  auto needs = [&](std::size_t k) {
    // (meets_own_box asks the world shapes first.)
    return geometry::boxes_overlap(box, shard_reach_[k]) &&
           ((keep_pins_ && pins_[k]) ? !world_shapes_miss(shard_reach_[k])
                                     : meets_own_box(shard_reach_[k], 0) &&
                                           index.tet_filter().planes_may_meet(shard_tet_[k], box));
  };
  if (index.options().prefetch) {
    // Several shards to page in: the prefetch thread loads them from the last while this
    // thread loads from the first (on two cores, a step entering a new region waits about half).
    hints_.clear();
    for (std::size_t k = 0; k < shards_.size(); ++k)
      if (!(keep_pins_ && pins_[k]) && needs(k) && !index.cache().contains(shards_[k]))
        hints_.push_back(shards_[k]);
    if (hints_.size() > 1) index.cache().prefetch_urgently(std::span(hints_).subspan(1));
  }
  for (std::size_t k = 0; k < shards_.size() && !stop; ++k) {
    const std::uint32_t shard_id = shards_[k];
    // Shards whose stored triangles cannot meet the object are neither read nor pinned.
    if (!needs(k)) continue;
    ++counters.shards_touched;
    ShardCache<Shard>::Pin local_pin;
    ShardCache<Shard>::Pin& pin = keep_pins_ ? pins_[k] : local_pin;
    if (!pin) {
      const auto acquire_start = Clock::now();
      const std::uint64_t misses_before = index.cache().miss_count();
      try {
        pin = index.cache().acquire(shard_id);
      } catch (const InputError&) {
        if (!keep_pins_) throw;
        // The budget cannot hold the region's pins after all: release them and go on one
        // shard at a time.
        keep_pins_ = false;
        pins_.clear();
        local_pin = index.cache().acquire(shard_id);
      }
      counters.shard_misses += std::uint32_t(index.cache().miss_count() - misses_before);
      counters.shard_seconds += seconds_since(acquire_start);
    }
    test_shard(keep_pins_ ? *pins_[k] : *local_pin);
  }
  if (all && result.contacts.size() > 1) {
    // A triangle that crosses regions is stored in each of their shards, and float copies are
    // each tested (above): report a pair once.
    auto key = [](const Contact& c) { return std::tie(c.environment_triangle, c.object_triangle); };
    std::sort(result.contacts.begin(), result.contacts.end(),
              [&](const Contact& a, const Contact& b) { return key(a) < key(b); });
    result.contacts.erase(std::unique(result.contacts.begin(), result.contacts.end()),
                          result.contacts.end());
  }
  const auto loop_end = Clock::now();
  counters.test_seconds = std::max(
      0.0, std::chrono::duration<double>(loop_end - loop_start).count() - counters.shard_seconds);
  if (!result.collides) check_containment(box, result, loop_end);
}

bool FlyingObject::step_in_new_free_box(const geometry::Box& box, QueryResult& result) {
  if (free_box_wait_ > 0) {
    --free_box_wait_;
    return false;
  }
  const auto start = Clock::now();
  const geometry::Box last = free_box_;
  const bool had_free_box = free_box_valid_;
  const bool found = find_free_box(box);
  const auto found_at = Clock::now();
  result.counters.free_box_seconds = std::chrono::duration<double>(found_at - start).count();
  if (!found) {
    // Near an obstacle the next steps fail too: try again after 1, 2, 4, then 8 steps.
    free_box_backoff_ =
        std::min<std::uint32_t>(std::max<std::uint32_t>(2 * free_box_backoff_, 1), 8);
    free_box_wait_ = free_box_backoff_;
    return false;
  }
  free_box_backoff_ = 0;
  result.counters.found_free_box = true;
  // No triangle's box meets the step's box: no candidates, no contact. The containment vertex
  // is on the last free box's side of every closed part when the two boxes' insides overlap
  // (their union is connected and holds no triangle); else the walk decides.
  const bool connected = had_free_box && last.lo[0] < free_box_.hi[0] &&
                         free_box_.lo[0] < last.hi[0] && last.lo[1] < free_box_.hi[1] &&
                         free_box_.lo[1] < last.hi[1] && last.lo[2] < free_box_.hi[2] &&
                         free_box_.lo[2] < last.hi[2];
  if (!connected) {
    check_containment(box, result, found_at);
    // Inside an obstacle: the box is not free space (steps inside it would answer so).
    if (result.collides) free_box_valid_ = false;
  }
  return true;
}

bool FlyingObject::find_free_box(const geometry::Box& box) {
  const CollisionIndex& index = *index_;
  // The box grown a little on every side (for rotations) and a few steps' motion ahead, within
  // the searched region: its tets' shards hold every triangle that meets it.
  // (0.0625 to 0.25 of the extent, 4 to 16 steps, and regions grown by 0.5 to 1 gave the same
  // rates within 3 % on the 1M demo's flights.)
  constexpr double kSlack = 0.125;
  constexpr double kStepsAhead = 8;
  const double slack = kSlack * geometry::extent(box);
  // How fast each side of the box moves outwards (the motion, and the rotation's growth).
  std::array<double, 6> speed{};
  if (previous_valid_)
    for (int a = 0; a < 3; ++a) {
      speed[2 * a] = std::max(0.0, previous_box_.lo[a] - current_box_.lo[a]);
      speed[2 * a + 1] = std::max(0.0, current_box_.hi[a] - previous_box_.hi[a]);
    }
  geometry::Box grown;
  // Within the mesh's box too: a step whose box lies inside the free box is inside the model.
  for (int a = 0; a < 3; ++a) {
    grown.lo[a] = std::max({searched_box_.lo[a], index.mesh_bounds().lo[a],
                            box.lo[a] - slack - kStepsAhead * speed[2 * a]});
    grown.hi[a] = std::min({searched_box_.hi[a], index.mesh_bounds().hi[a],
                            box.hi[a] + slack + kStepsAhead * speed[2 * a + 1]});
  }
  // Cut away each triangle box (or unread shard's reach) that meets the grown box, on a side
  // where it is apart from the step's box: the side the box takes longest to reach.
  const double slowest = 0.01 * geometry::extent(box);
  auto cut = [&](const geometry::Box& obstacle) {
    if (!geometry::boxes_overlap(grown, obstacle)) return true;
    int best_side = -1;
    double best_steps = -1;
    for (int a = 0; a < 3; ++a) {
      if (obstacle.hi[a] < box.lo[a]) {
        const double steps = (box.lo[a] - obstacle.hi[a]) / std::max(speed[2 * a], slowest);
        if (steps > best_steps) best_steps = steps, best_side = 2 * a;
      }
      if (obstacle.lo[a] > box.hi[a]) {
        const double steps = (obstacle.lo[a] - box.hi[a]) / std::max(speed[2 * a + 1], slowest);
        if (steps > best_steps) best_steps = steps, best_side = 2 * a + 1;
      }
    }
    if (best_side < 0) return false;  // it overlaps the step's box itself
    const int a = best_side / 2;
    if (best_side % 2 == 1)
      grown.hi[a] = std::min(grown.hi[a], obstacle.lo[a]);
    else
      grown.lo[a] = std::max(grown.lo[a], obstacle.hi[a]);
    return true;
  };
  bool found = true;
  for (std::size_t k = 0; k < shards_.size() && found; ++k) {
    if (!geometry::boxes_overlap(grown, shard_reach_[k]) ||
        !index.tet_filter().planes_may_meet(shard_tet_[k], grown))
      continue;
    const Shard* shard = nullptr;
    if (keep_pins_ && !pins_[k] && index.cache().contains(shards_[k])) {
      try {
        pins_[k] = index.cache().acquire(shards_[k]);
      } catch (const InputError&) {
        // evicted meanwhile, and the budget holds no more pins: cut its reach instead
      }
    }
    if (keep_pins_ && pins_[k]) shard = &*pins_[k];
    if (shard == nullptr) {
      // Not resident: its triangles within the grown box lie in its reach, or in another tet
      // of the region whose shard holds them too. Cut the reach rather than page it in.
      found = cut(shard_reach_[k]);
      continue;
    }
    // A leaf or cell apart from the step's box is cut whole (its box holds its triangles'
    // points that the query reaches): a few tests instead of one per triangle.
    shard->for_each_box_candidate(
        grown,
        [&](const geometry::Box& leaf, std::uint32_t) {
          if (!found || geometry::boxes_overlap(leaf, box)) return found;
          found = cut(leaf);
          return false;
        },
        [&](std::uint32_t, const geometry::Triangle& triangle) {
          if (found) found = cut(geometry::box_of(triangle));
        });
  }
  // A failed search keeps the last free box: it still holds no triangle.
  if (found) free_box_ = grown, free_box_valid_ = true;
  return found;
}

void FlyingObject::check_containment(const geometry::Box& box, QueryResult& result,
                                     std::chrono::steady_clock::time_point start) {
  check_object_inside_obstacle(result);
  if (!result.collides) check_obstacle_inside_object(box, result);
  result.counters.interior_seconds = seconds_since(start);
}

void FlyingObject::check_object_inside_obstacle(QueryResult& result) {
  // With no surface contact, one vertex of each of the object's components decides for the
  // whole component (it is connected and crosses no surface).
  if (!index_->has_interiors()) return;
  const std::size_t components = model_->component_vertices.size();
  if (interior_memos_.size() != components)
    interior_memos_.assign(components, {}), interior_tets_.assign(components, 0);
  for (std::size_t c = 0; c < components && !result.collides; ++c) {
    const ObstacleQuery inside =
        locate_in_obstacles(*index_, interior_tets_[c], world_vertex(model_->component_vertices[c]),
                            interior_memos_[c], std::span<const ShardPin>(pins_));
    if (inside.containment == ObstacleContainment::inside) {
      result.collides = true;
      result.containment = Containment::object_inside_obstacle;
      result.containing_component = inside.component;
      result.containing_part = index_->component_part(inside.component);
    }
  }
}

void FlyingObject::check_obstacle_inside_object(const geometry::Box& box, QueryResult& result) {
  // An environment component whose box lies in the object's box, touching no object surface,
  // lies wholly inside or wholly outside every closed component of the object: one vertex
  // decides. Most vertices are far from the object's surface, where the interior grid answers
  // at once; the rest need a parity count.
  std::sort(enclosed_.begin(), enclosed_.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  enclosed_.erase(std::unique(enclosed_.begin(), enclosed_.end(),
                              [](const auto& a, const auto& b) { return a.first == b.first; }),
                  enclosed_.end());
  const auto inside = [&](std::uint32_t component) {
    result.collides = true;
    result.containment = Containment::obstacle_inside_object;
    result.containing_component = component;
    result.containing_part = index_->component_part(component);
  };
  std::size_t undecided = 0;
  for (std::size_t i = 0; i < enclosed_.size() && !result.collides; ++i) {
    const geometry::Point& p = enclosed_[i].second;
    switch (model_->interior_grid.classify(to_object_frame(p), frame_margin(p))) {
      case ObjectInteriorGrid::Side::inside:
        inside(enclosed_[i].first);
        break;
      case ObjectInteriorGrid::Side::outside:
        break;
      case ObjectInteriorGrid::Side::unknown:
        enclosed_[undecided++] = enclosed_[i];
        break;
    }
  }
  enclosed_.resize(undecided);
  for (std::size_t i = 0; i < enclosed_.size() && !result.collides; ++i)
    if (crossing_parity_holds(enclosed_[i].second, box)) inside(enclosed_[i].first);
}

Vec3 FlyingObject::to_object_frame(const geometry::Point& p) const {
  const Vec3 e{p[0] - translation_[0], p[1] - translation_[1], p[2] - translation_[2]};
  return {rotation_[0] * e[0] + rotation_[3] * e[1] + rotation_[6] * e[2],
          rotation_[1] * e[0] + rotation_[4] * e[1] + rotation_[7] * e[2],
          rotation_[2] * e[0] + rotation_[5] * e[1] + rotation_[8] * e[2]};
}

bool FlyingObject::in_object_box(const geometry::Point& p) const {
  // p in the object's own frame (rounded back, so the box is grown far beyond the rounding):
  // outside that box means outside the object. The world box is looser for a rotated object.
  const Vec3 x = to_object_frame(p);
  const double margin = frame_margin(p);
  for (int a = 0; a < 3; ++a)
    if (x[a] < model_->box.lo[a] - margin || x[a] > model_->box.hi[a] + margin) return false;
  return true;
}

double FlyingObject::frame_margin(const geometry::Point& p) const {
  // Far beyond the rounding of to_object_frame and of the placement: a point this close to
  // the object's box or surface is left to the exact tests.
  return (model_->radius + std::max({std::fabs(p[0]), std::fabs(p[1]), std::fabs(p[2])}) +
          std::max({std::fabs(translation_[0]), std::fabs(translation_[1]),
                    std::fabs(translation_[2])})) *
         0x1p-40;
}

bool FlyingObject::crossing_parity_holds(const geometry::Point& p, const geometry::Box& box) {
  // Parity of crossings with the placed object along a segment from p to beyond the object's
  // box; a direction whose segment meets an edge, a vertex or a plane is replaced by the next.
  // Directions are nearly along the object's own axes, so that the segment's box in the
  // object's frame is thin and the BVH offers few triangles; slanted, so that the segment
  // misses the vertices that generated objects put on their axes.
  static constexpr std::array<std::array<double, 3>, 6> kDirections{
      {{0.0123457, 0.0345679, 0.99932},
       {0.99932, 0.0123457, 0.0345679},
       {0.0345679, 0.99932, 0.0123457},
       {-0.0234567, 0.0156789, -0.99960},
       {-0.99960, -0.0234567, 0.0156789},
       {0.0156789, -0.99960, -0.0234567}}};
  // |d| = 1, so some coordinate moves by reach / sqrt(3) > the box's largest side.
  const double reach =
      2 * std::max({box.hi[0] - box.lo[0], box.hi[1] - box.lo[1], box.hi[2] - box.lo[2]});
  for (const auto& o : kDirections) {
    const Vec3 d{rotation_[0] * o[0] + rotation_[1] * o[1] + rotation_[2] * o[2],
                 rotation_[3] * o[0] + rotation_[4] * o[1] + rotation_[5] * o[2],
                 rotation_[6] * o[0] + rotation_[7] * o[1] + rotation_[8] * o[2]};
    const geometry::Point far{p[0] + d[0] * reach, p[1] + d[1] * reach, p[2] + d[2] * reach};
    const geometry::Segment segment{p, far};
    // The segment's box in the object's frame (rounded: it only prunes), as in phase II.
    geometry::Box query;
    double magnitude = model_->radius;
    for (const auto& q : segment) {
      query.extend(to_object_frame(q));
      for (int a = 0; a < 3; ++a)
        magnitude = std::max(magnitude, std::fabs(q[a]) + std::fabs(translation_[a]));
    }
    const double grow = magnitude * 0x1p-40;
    for (int a = 0; a < 3; ++a) query.lo[a] -= grow, query.hi[a] += grow;
    if (const auto odd = crossing_parity(model_->bvh, model_->closed_components, segment, query,
                                         [&](std::uint32_t t) { return world_triangle(t); }))
      return *odd;
  }
  return false;  // every direction grazed the object: taken as outside
}

}  // namespace tetrapage
