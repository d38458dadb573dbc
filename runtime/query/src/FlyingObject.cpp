#include "tetrapage/runtime/query/FlyingObject.h"

#include <algorithm>
#include <chrono>
#include <string>

#include "FlyingObjectParts.h"
#include "PhaseTwo.h"
#include "StepClock.h"
#include "tetrapage/formats/base/Error.h"

namespace tetrapage {

namespace {

// A step's answer starts empty (its buffers are reused).
void clear_answer(QueryResult& result) {
  result.collides = false;
  result.containment = Containment::none;
  result.containing_part = 0;
  result.containing_component = 0;
  result.containing_dynamic_part = 0;
  result.contacts.clear();
  result.outside_model = false;
  result.counters = {};
}

// What a step asks of the object, by its options and whether a previous pose exists.
struct Question {
  Question(const QueryOptions& options, bool has_previous)
      : swept(options.motion == Motion::swept && has_previous),
        solid(options.shape != ObjectShape::mesh || swept),
        own_frame(!solid || (options.shape == ObjectShape::hull && !swept)) {}
  bool swept;  ///< the motion from the previous pose, not this pose alone
  /// The object as a solid (hull or box, or swept between the poses), not as its mesh.
  bool solid;
  /// Phase I prunes with the object's own box, ball and hull in its frame: the question is
  /// about the current pose's object or its hull (both inside that box), not its world box or
  /// a swept solid.
  bool own_frame;
};

// The world box grown into phase I's box; returns the accuracy's reach.
double grow_to_phase_one_box(geometry::Box& box, const QueryOptions& options,
                             const Question& question, const Coherence& coherence) {
  // The phase I box covers both poses of a swept step.
  if (question.swept) box.extend(coherence.previous_box());
  // Environment triangles within the accuracy's reach of the object count: grow the box.
  const double reach =
      geometry::collision_margin(options.accuracy, geometry::extent(box), geometry::extent(box));
  if (question.solid)
    box = reach > 0 ? geometry::inflated(box, reach) : box;  // covers the solid box's own growth
  else if (reach > 0)
    for (int a = 0; a < 3; ++a) box.lo[a] -= reach, box.hi[a] += reach;
  return reach;
}

}  // namespace

FlyingObject::FlyingObject(std::shared_ptr<const CollisionIndex> index, TriangleSoup object)
    : FlyingObject(std::move(index), std::make_shared<const ObjectModel>(std::move(object))) {}

FlyingObject::FlyingObject(std::shared_ptr<const CollisionIndex> index,
                           std::shared_ptr<const ObjectModel> model)
    : index_(std::move(index)), model_(std::move(model)) {
  if (!index_) throw InputError("a flying object needs an index");
  if (!model_) throw InputError("a flying object needs an object model");
  parts_ = std::make_unique<Parts>(*index_, *model_);
}

FlyingObject::~FlyingObject() = default;
FlyingObject::FlyingObject(FlyingObject&&) noexcept = default;
FlyingObject& FlyingObject::operator=(FlyingObject&&) noexcept = default;

geometry::Box FlyingObject::world_box(const Pose& pose) {
  parts_->object.place(pose);
  return parts_->object.world_box();
}

void FlyingObject::query(const Pose& pose, const QueryOptions& options, QueryResult& result) {
  Parts& parts = *parts_;
  const CollisionIndex& index = *index_;
  clear_answer(result);
  parts.contact_triangles.clear();
  StepCounters& counters = result.counters;
  const DynamicObstacles* overlay = parts.obstacles.get();
  parts.containment.begin_step(overlay);
  // A changed overlay may have put a part into the free box.
  if (overlay != nullptr && overlay->version() != parts.obstacles_version) {
    parts.coherence.obstacles_changed(overlay, overlay->shows() != parts.obstacles_shows);
    parts.obstacles_version = overlay->version();
    parts.obstacles_shows = overlay->shows();
  }

  // The step, numbered as docs/ARCHITECTURE.md, "The runtime step", numbers it.
  // 1. The pose and the world box. A step that may end inside the free box reads no clock
  // before it knows (two reads were a tenth of such a step's time); its box's time is then
  // not counted.
  const bool time_box = !parts.coherence.has_free_box();
  Clock::time_point start;
  if (time_box) start = Clock::now();
  geometry::Box box = world_box(pose);
  parts.coherence.begin_step(box);
  // Whatever way this query leaves, its pose is the next one's previous pose (swept motion).
  struct RememberPose {
    Parts& parts;
    ~RememberPose() { parts.coherence.remember(parts.object); }
  } remember{parts};
  const Question question(options, parts.coherence.has_previous());
  const double reach = grow_to_phase_one_box(box, options, question, parts.coherence);
  result.world_box = box;
  if (parts.coherence.in_free_box(box)) {
    // (The free box lies in the mesh's box: the object is not outside the model.)
    counters.in_free_box = true;
    return;
  }
  // The clock's reads were 6 % of the time of a flight of free steps (perf): one reading ends a
  // phase and starts the next.
  Clock::time_point phase_start = Clock::now();
  if (time_box)
    counters.locate_seconds = std::chrono::duration<double>(phase_start - start).count();

  // 2. When the box leaves the searched region: the walk, the box search, the region's shards.
  // Outside the model, dynamic obstacles may still stand.
  if (!geometry::boxes_overlap(box, index.mesh_bounds())) {
    outside_model(result);
    return test_obstacles_alone(box, options, question.own_frame, question.solid, reach, result);
  }
  if (!parts.region.contains(box)) {
    // A centre outside the convex mesh: the box meets only the model's empty margin.
    if (!parts.region.search(box, parts.coherence.motion(), counters)) {
      outside_model(result);
      return test_obstacles_alone(box, options, question.own_frame, question.solid, reach, result);
    }
    phase_start = Clock::now();
  }

  // 3. A free box: most steps far from obstacles find a box around them that holds no
  // triangle, and then need no phase I; the next steps inside it need nothing else.
  if (step_in_new_free_box(box, result)) return;

  // 4. Phase I over the region's shards whose bounds meet the box, 5. phase II over their
  // candidates (test_region), 6. then containment.
  parts.shapes.prepare(*model_, parts.object, box, reach, question.own_frame, question.solid,
                       shapes_box(box));
  test_region(box, options, question.solid, phase_start, result);
}

void FlyingObject::outside_model(QueryResult& result) {
  result.outside_model = true;
  parts_->region.release();
}

bool FlyingObject::step_in_new_free_box(const geometry::Box& box, QueryResult& result) {
  Parts& parts = *parts_;
  const Coherence::NewFreeBox found = parts.coherence.look_for_free_box(
      box, parts.region, *index_, parts.obstacles.get(), result.counters);
  if (!found.found) return false;
  if (!found.connected) {
    parts.containment.check(box, parts.object, parts.region.pins(), result, found.at);
    // Inside an obstacle: the box is not free space (steps inside it would answer so).
    if (result.collides) parts.coherence.drop_free_box();
  }
  return true;
}

void FlyingObject::test_region(const geometry::Box& box, const QueryOptions& options,
                               bool solid_query, std::chrono::steady_clock::time_point loop_start,
                               QueryResult& result) {
  Parts& parts = *parts_;
  const CollisionIndex& index = *index_;
  StepCounters& counters = result.counters;
  SearchedRegion& region = parts.region;
  const PruningShapes& shapes = parts.shapes;
  // Does this step need shard k? Only if its box meets the shard's reach and, before the shard
  // is pinned (a page-in is dearer than the test), the object's own box meets it in its frame:
  // a contact point, or a point of a triangle inside the object, lies in the object and in some
  // tet of the region, within that tet's reach, and that tet's shard holds the triangle.
  // Before a page-in also the tet itself, by its face planes: the coarse tets are slivers
  // whose boxes reach far beyond them.
  auto needs = [&](std::size_t k) {
    // (meets_own_box asks the world shapes first.)
    return geometry::boxes_overlap(box, region.reach(k)) &&
           (region.pinned(k) ? !shapes.world_shapes_miss(region.reach(k))
                             : shapes.meets_own_box(region.reach(k), 0) &&
                                   index.tet_filter().planes_may_meet(region.tet(k), box));
  };
  region.prefetch_needed(needs);
  PhaseTwo phase_two(parts.step_context(index, *model_, result), options, solid_query, box);
  // One clock pair around the loop (a free step is a few microseconds; a clock read per shard
  // cost a tenth of it): the tests' time is the loop's less the acquisitions'.
  for (std::size_t k = 0; k < region.size() && !phase_two.stopped(); ++k) {
    // Shards whose stored triangles cannot meet the object are neither read nor pinned.
    if (!needs(k)) continue;
    ++counters.shards_touched;
    ShardPin local_pin;
    phase_two.test_shard(region.acquire(k, local_pin, counters), parts.obstacles.get());
  }
  if (parts.obstacles && !phase_two.stopped())
    phase_two.test_dynamic_parts(*parts.obstacles, parts.obstacle);
  phase_two.finish();
  const auto loop_end = Clock::now();
  counters.test_seconds = std::max(
      0.0, std::chrono::duration<double>(loop_end - loop_start).count() - counters.shard_seconds);
  if (!result.collides) parts.containment.check(box, parts.object, region.pins(), result, loop_end);
  parts.containment.check_dynamic(box, parts.object, parts.obstacle, solid_query, result);
}

geometry::Box FlyingObject::shapes_box(const geometry::Box& box) const {
  // The pruning shapes' margins scale with the coordinates they meet: the mesh's, and with
  // dynamic obstacles (which may stand outside it) the step's box's too.
  geometry::Box covered = index_->mesh_bounds();
  if (parts_->obstacles) covered.extend(box);
  return covered;
}

void FlyingObject::test_obstacles_alone(const geometry::Box& box, const QueryOptions& options,
                                        bool own_frame, bool solid_query, double reach,
                                        QueryResult& result) {
  Parts& parts = *parts_;
  if (!parts.obstacles || parts.obstacles->size() == 0) return;
  parts.shapes.prepare(*model_, parts.object, box, reach, own_frame, solid_query, shapes_box(box));
  PhaseTwo phase_two(parts.step_context(*index_, *model_, result), options, solid_query, box);
  phase_two.test_dynamic_parts(*parts.obstacles, parts.obstacle);
  phase_two.finish();
  parts.containment.check_dynamic(box, parts.object, parts.obstacle, solid_query, result);
}

void FlyingObject::set_obstacles(std::shared_ptr<const DynamicObstacles> obstacles) {
  if (obstacles && obstacles->index() != index_)
    throw InputError("dynamic obstacles on another index (" + obstacles->index()->path().string() +
                     ") than the flying object's (" + index_->path().string() + ")");
  parts_->obstacles = std::move(obstacles);
  parts_->coherence.drop_free_box();  // the free box did not know them
  parts_->obstacles_version = parts_->obstacles ? parts_->obstacles->version() : 0;
  parts_->obstacles_shows = parts_->obstacles ? parts_->obstacles->shows() : 0;
}

std::pair<geometry::Triangle, geometry::Triangle> FlyingObject::dynamic_contact_triangles(
    const Contact& contact) {
  const DynamicObstacles::Part* part =
      parts_->obstacles ? parts_->obstacles->find(contact.dynamic_part) : nullptr;
  if (part == nullptr)
    throw InputError("contact geometry: no dynamic part " + std::to_string(contact.dynamic_part));
  if (contact.environment_triangle >= part->model->mesh.triangles.size() ||
      contact.object_triangle >= model_->mesh.triangles.size())
    throw InputError("contact geometry: dynamic part " + std::to_string(contact.dynamic_part) +
                     " has no triangle " + std::to_string(contact.environment_triangle) +
                     " or the object no triangle " + std::to_string(contact.object_triangle));
  PlacedObject placed(*part->model);
  placed.place(part->pose);
  return {placed.world_triangle(std::uint32_t(contact.environment_triangle)),
          parts_->object.world_triangle(contact.object_triangle)};
}

const std::shared_ptr<const DynamicObstacles>& FlyingObject::obstacles() const {
  return parts_->obstacles;
}

}  // namespace tetrapage
