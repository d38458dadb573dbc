// The C API (tetrapage.h) over CollisionIndex and FlyingObject. Every entry point runs its
// body inside guarded(), which turns every exception into a status and a thread-local message:
// nothing thrown in C++ may unwind through a C caller's frames.
//
// Handles are ids, never addresses: each is looked up in a process-wide table under a lock,
// so a handle released already (or never issued) is found missing and reported, never
// dereferenced. Ids come from one 64-bit counter and are never reused, so a stale handle
// cannot alias a newer index or object. Both, shared with CApiGroup.cpp, are in CApiSupport.h.

#include "tetrapage/tetrapage.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <utility>

#include "CApiSupport.h"
#include "tetrapage/formats/base/ByteSize.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/runtime/geometry/Accuracy.h"
#include "tetrapage/runtime/paging/CollisionIndex.h"
#include "tetrapage/runtime/query/FlyingObject.h"

using namespace tetrapage::capi;

// A C header cannot read the C++ constant: the macro restates it, and this keeps them equal.
static_assert(
    TETRAPAGE_DEFAULT_BUDGET_BYTES == tetrapage::kDefaultMemoryBudget,
    "tetrapage.h's TETRAPAGE_DEFAULT_BUDGET_BYTES must equal ByteSize.h's kDefaultMemoryBudget");

namespace {

/// `accuracy`: a tetrapage_accuracy read by caller_value.
tetrapage::geometry::Accuracy to_accuracy(int accuracy, double parameter) {
  using tetrapage::geometry::Accuracy;
  const bool epsilon_valid = std::isfinite(parameter) && parameter >= 0;
  switch (accuracy) {
    case TETRAPAGE_ACCURACY_EXACT:
      return Accuracy::exact();
    case TETRAPAGE_ACCURACY_DOUBLE_EPS:
    case TETRAPAGE_ACCURACY_FLOAT_EPS:
      if (!epsilon_valid)
        throw tetrapage::InputError("the relative epsilon must be finite and >= 0, not " +
                                    std::to_string(parameter));
      return accuracy == TETRAPAGE_ACCURACY_DOUBLE_EPS ? Accuracy::double_eps(parameter)
                                                       : Accuracy::float_eps(parameter);
    case TETRAPAGE_ACCURACY_CLEARANCE:
      return Accuracy::within(parameter);
  }
  throw tetrapage::InputError("unknown accuracy " + std::to_string(accuracy));
}

// The header restates the C++ conventions of a contact site; these keep them equal.
static_assert(TETRAPAGE_NO_OBJECT_TRIANGLE == tetrapage::Contact::kNoObjectTriangle);
static_assert(TETRAPAGE_DYNAMIC_PART == tetrapage::Contact::kDynamicPart);
static_assert(TETRAPAGE_NO_TRIANGLE == tetrapage::ContactSite::kNoTriangle);
static_assert(TETRAPAGE_NO_COMPONENT == tetrapage::ContactSite::kNoComponent);

// An argument struct grows by fields appended at its end; read_args copies an older caller's
// struct_size bytes over the defaults, which is right only if those bytes hold no padding a
// newer field could occupy: no struct may end in padding.
template <class Args, class Last>
constexpr bool ends_without_padding(std::size_t last_offset) {
  return last_offset + sizeof(Last) == sizeof(Args);
}
static_assert(ends_without_padding<tetrapage_query_args, std::uint64_t>(
    offsetof(tetrapage_query_args, max_contacts)));
static_assert(ends_without_padding<tetrapage_distance_args, double>(
    offsetof(tetrapage_distance_args, max_distance)));
static_assert(ends_without_padding<tetrapage_impact_args, std::uint64_t>(
    offsetof(tetrapage_impact_args, max_iterations)));

// The C++ site's fields and "none" conventions are the C hit's (asserted above).
tetrapage_hit hit_of(const tetrapage::ContactSite& contact) {
  return {contact.environment_triangle, contact.environment_part, contact.environment_component,
          contact.object_triangle, contact.dynamic_part};
}

}  // namespace

extern "C" {

const char* tetrapage_version(void) { return TETRAPAGE_VERSION_STRING; }

const char* tetrapage_last_error(void) { return last_error_message.c_str(); }

const char* tetrapage_status_string(tetrapage_status status) {
  switch (caller_value(status)) {
    case TETRAPAGE_OK: return "ok";
    case TETRAPAGE_ERROR_IO: return "I/O error";
    case TETRAPAGE_ERROR_FORMAT: return "format error";
    case TETRAPAGE_ERROR_INPUT: return "input error";
    case TETRAPAGE_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case TETRAPAGE_ERROR_OUT_OF_MEMORY: return "out of memory";
    case TETRAPAGE_ERROR_INTERNAL: return "internal error";
    case TETRAPAGE_ERROR_STALE_HANDLE: return "stale handle";
  }
  return "unknown status";
}

tetrapage_status tetrapage_open(const char* path, uint64_t budget_bytes, tetrapage_index** index) {
  if (index) *index = nullptr;
  return guarded(__func__, [&] {
    require(path, "path");
    require(index, "index");
    tetrapage::CollisionIndexOptions options;
    options.memory_budget_bytes = budget_bytes;
    auto opened = std::make_shared<IndexState>();
    opened->index = std::make_shared<const tetrapage::CollisionIndex>(path, options);
    *index = reinterpret_cast<tetrapage_index*>(indexes().add(std::move(opened)));
  });
}

tetrapage_status tetrapage_close(tetrapage_index* index) {
  return guarded(__func__, [&] {
    if (index == nullptr) return;
    // The last reference (unless objects hold the index) goes here, outside the table's lock.
    indexes().remove(id_of(index)).reset();
  });
}

tetrapage_status tetrapage_index_bounds(const tetrapage_index* index, double lo[3], double hi[3]) {
  return guarded(__func__, [&] {
    const auto state = index_state(index);
    require(lo, "lo");
    require(hi, "hi");
    const auto& bounds = state->index->header().bounds;
    for (int a = 0; a < 3; ++a) {
      lo[a] = bounds.lo[a];
      hi[a] = bounds.hi[a];
    }
  });
}

namespace {

// The C API's string convention (tetrapage.h): copied, cut to fit, NUL-terminated, and the
// whole length returned.
void copy_string(const std::string& text, char* buffer, size_t capacity, size_t* length) {
  require(length, "length");
  if (capacity > 0) {
    require(buffer, "buffer");
    const size_t copied = std::min(capacity - 1, text.size());
    std::memcpy(buffer, text.data(), copied);
    buffer[copied] = '\0';
  }
  *length = text.size();
}

std::uint32_t checked_part(const tetrapage::CollisionIndex& index, uint32_t part) {
  if (part >= index.parts().count())
    throw tetrapage::InputError(index.path().string() + ": no part " + std::to_string(part) + " (the model has " +
                                std::to_string(index.parts().count()) + ")");
  return part;
}

}  // namespace

tetrapage_status tetrapage_index_part_count(const tetrapage_index* index, uint32_t* count) {
  return guarded(__func__, [&] {
    const auto state = index_state(index);
    require(count, "count");
    *count = uint32_t(state->index->parts().count());
  });
}

tetrapage_status tetrapage_index_part_name(const tetrapage_index* index, uint32_t part, char* buffer,
                                           size_t capacity, size_t* length) {
  return guarded(__func__, [&] {
    const auto state = index_state(index);
    copy_string(state->index->parts().name(checked_part(*state->index, part)), buffer, capacity, length);
  });
}

tetrapage_status tetrapage_index_part_path(const tetrapage_index* index, uint32_t part, char* buffer,
                                           size_t capacity, size_t* length) {
  return guarded(__func__, [&] {
    const auto state = index_state(index);
    copy_string(state->index->parts().path(checked_part(*state->index, part)), buffer, capacity, length);
  });
}

tetrapage_status tetrapage_index_length_unit(const tetrapage_index* index, char* buffer, size_t capacity,
                                             size_t* length) {
  return guarded(__func__, [&] {
    const auto state = index_state(index);
    copy_string(state->index->header().length_unit, buffer, capacity, length);
  });
}

tetrapage_status tetrapage_index_triangle(const tetrapage_index* index, uint64_t id, double corners[9],
                                          uint32_t* part) {
  return guarded(__func__, [&] {
    const auto state = index_state(index);
    require(corners, "corners");
    require(part, "part");
    const auto stored = state->index->stored_triangle(id);
    if (!stored)
      throw tetrapage::InputError(state->index->path().string() + ": no stored triangle has id " + std::to_string(id));
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) corners[3 * k + a] = stored->corners[k][a];
    *part = state->index->component_part(stored->component);
  });
}

tetrapage_status tetrapage_object_create(tetrapage_index* index, const double* vertices,
                                         size_t vertex_count, const uint32_t* triangles,
                                         size_t triangle_count, tetrapage_object** object) {
  if (object) *object = nullptr;
  return guarded(__func__, [&] {
    const auto state = index_state(index);
    require(object, "object");
    if (vertex_count > 0) require(vertices, "vertices");
    if (triangle_count > 0) require(triangles, "triangles");
    auto soup = object_soup(vertices, vertex_count, triangles, triangle_count);
    auto created = std::make_shared<ObjectState>(
        ObjectState{tetrapage::FlyingObject(state->index, std::move(soup)), {}, false});
    *object = reinterpret_cast<tetrapage_object*>(objects().add(std::move(created)));
  });
}

tetrapage_status tetrapage_object_create_from_file(tetrapage_index* index, const char* path,
                                                   tetrapage_object** object) {
  if (object) *object = nullptr;
  return guarded(__func__, [&] {
    const auto state = index_state(index);
    require(path, "path");
    require(object, "object");
    auto created = std::make_shared<ObjectState>(
        ObjectState{tetrapage::FlyingObject(state->index, tetrapage::read_mesh(path)), {}, false});
    *object = reinterpret_cast<tetrapage_object*>(objects().add(std::move(created)));
  });
}

tetrapage_status tetrapage_object_destroy(tetrapage_object* object) {
  return guarded(__func__, [&] {
    if (object == nullptr) return;
    objects().remove(id_of(object)).reset();
  });
}

tetrapage_status tetrapage_parse_accuracy(const char* text, tetrapage_accuracy* accuracy,
                                          double* parameter) {
  return guarded(__func__, [&] {
    require(text, "text");
    require(accuracy, "accuracy");
    require(parameter, "parameter");
    const auto parsed = tetrapage::geometry::parse_accuracy(text);
    switch (parsed.mode) {
      case tetrapage::geometry::AccuracyMode::exact:
        *accuracy = TETRAPAGE_ACCURACY_EXACT;
        *parameter = 0;
        break;
      case tetrapage::geometry::AccuracyMode::double_eps:
        *accuracy = TETRAPAGE_ACCURACY_DOUBLE_EPS;
        *parameter = parsed.relative_epsilon;
        break;
      case tetrapage::geometry::AccuracyMode::float_eps:
        *accuracy = TETRAPAGE_ACCURACY_FLOAT_EPS;
        *parameter = parsed.relative_epsilon;
        break;
      case tetrapage::geometry::AccuracyMode::clearance:
        *accuracy = TETRAPAGE_ACCURACY_CLEARANCE;
        *parameter = parsed.clearance;
        break;
    }
  });
}

void tetrapage_query_args_init(tetrapage_query_args* args) {
  if (args == nullptr) return;
  *args = tetrapage_query_args{};
  args->struct_size = sizeof(tetrapage_query_args);
  args->accuracy = TETRAPAGE_ACCURACY_EXACT;
  args->shape = TETRAPAGE_SHAPE_MESH;
  args->motion = TETRAPAGE_MOTION_DISCRETE;
  args->contacts = TETRAPAGE_CONTACTS_FIRST;
  args->max_contacts = tetrapage::kDefaultMaxContacts;
}

}  // extern "C"

namespace {

// A C enumeration's value as the C++ enumerator of the same rank (the C values are 0, 1, ...).
template <class Enum, std::size_t N>
Enum enumerator_of(std::int32_t value, const Enum (&enumerators)[N], const char* what) {
  if (value < 0 || std::size_t(value) >= N)
    throw tetrapage::InputError(std::string("unknown ") + what + " " + std::to_string(value));
  return enumerators[value];
}
static_assert(TETRAPAGE_SHAPE_MESH == 0 && TETRAPAGE_SHAPE_HULL == 1 && TETRAPAGE_SHAPE_BOX == 2);
static_assert(TETRAPAGE_MOTION_DISCRETE == 0 && TETRAPAGE_MOTION_SWEPT == 1);
static_assert(TETRAPAGE_CONTACTS_FIRST == 0 && TETRAPAGE_CONTACTS_ALL == 1);

tetrapage::QueryOptions to_query_options(const tetrapage_query_args& args) {
  using tetrapage::Motion, tetrapage::ObjectShape, tetrapage::QueryMode;
  tetrapage::QueryOptions options;
  options.accuracy = to_accuracy(args.accuracy, args.parameter);
  options.shape = enumerator_of(
      args.shape, {ObjectShape::mesh, ObjectShape::hull, ObjectShape::box}, "object shape");
  options.motion = enumerator_of(args.motion, {Motion::discrete, Motion::swept}, "motion");
  options.mode = enumerator_of(args.contacts, {QueryMode::first_hit, QueryMode::all_contacts},
                               "contacts value");
  if (args.max_contacts == 0) throw tetrapage::InputError("max_contacts must be at least 1, not 0");
  options.max_contacts = std::size_t(std::min<std::uint64_t>(args.max_contacts, SIZE_MAX));
  return options;
}

tetrapage::Pose pose_of(const double pose[7]) {
  tetrapage::Pose placed;
  placed.translation = {pose[0], pose[1], pose[2]};
  placed.rotation = {pose[3], pose[4], pose[5], pose[6]};
  return placed;
}

// tetrapage_collide and the deprecated tetrapage_query: `args` read already.
tetrapage_status collide(const char* function, tetrapage_object* object, const double pose[7],
                         const tetrapage_query_args* args, int* collides) {
  if (collides) *collides = 0;
  return guarded(function, [&] {
    const auto state = object_state(object);
    state->has_result = false;  // a failed query leaves no contact behind
    require(pose, "pose");
    require(collides, "collides");
    tetrapage_query_args defaults;
    tetrapage_query_args_init(&defaults);
    const tetrapage::QueryOptions options = to_query_options(read_args(args, defaults, "args"));
    state->flying.query(pose_of(pose), options, state->result);
    state->has_result = true;
    *collides = state->result.collides ? 1 : 0;
  });
}

}  // namespace

extern "C" {

tetrapage_status tetrapage_collide(tetrapage_object* object, const double pose[7],
                                   const tetrapage_query_args* args, int* collides) {
  return collide(__func__, object, pose, args, collides);
}

tetrapage_status tetrapage_query(tetrapage_object* object, const double pose[7],
                                 tetrapage_accuracy accuracy, double parameter, int all_contacts,
                                 int* collides) {
  tetrapage_query_args args;
  tetrapage_query_args_init(&args);
  args.accuracy = caller_value(accuracy);  // an enum outside its enumerators is not loaded
  args.parameter = parameter;
  args.contacts = all_contacts ? TETRAPAGE_CONTACTS_ALL : TETRAPAGE_CONTACTS_FIRST;
  return collide(__func__, object, pose, &args, collides);
}

tetrapage_status tetrapage_contact_count(const tetrapage_object* object, size_t* count) {
  if (count) *count = 0;
  return guarded(__func__, [&] {
    const auto state = object_state(object);
    require(count, "count");
    *count = state->has_result ? state->result.contacts.size() : 0;
  });
}

tetrapage_status tetrapage_get_contacts(const tetrapage_object* object,
                                        tetrapage_contact* contacts, size_t capacity,
                                        size_t* written) {
  if (written) *written = 0;
  return guarded(__func__, [&] {
    const auto state = object_state(object);
    require(written, "written");
    if (capacity > 0) require(contacts, "contacts");
    if (!state->has_result) return;
    const auto& found = state->result.contacts;
    const std::size_t n = std::min(capacity, found.size());
    for (std::size_t i = 0; i < n; ++i)
      contacts[i] = {found[i].environment_triangle, found[i].environment_part, found[i].object_triangle,
                     found[i].environment_component};
    *written = n;
  });
}

tetrapage_status tetrapage_get_hits(const tetrapage_object* object, tetrapage_hit* hits,
                                    size_t capacity, size_t* written) {
  if (written) *written = 0;
  return guarded(__func__, [&] {
    const auto state = object_state(object);
    require(written, "written");
    if (capacity > 0) require(hits, "hits");
    if (!state->has_result) return;
    const auto& found = state->result.contacts;
    const std::size_t n = std::min(capacity, found.size());
    for (std::size_t i = 0; i < n; ++i) hits[i] = hit_of(found[i]);
    *written = n;
  });
}

tetrapage_status tetrapage_last_query_info(const tetrapage_object* object,
                                           tetrapage_query_info* info) {
  return guarded(__func__, [&] {
    const auto state = object_state(object);
    require(info, "info");
    *info = tetrapage_query_info{};
    if (!state->has_result) return;
    const auto& result = state->result;
    const auto& counters = result.counters;
    info->collides = result.collides ? 1 : 0;
    info->outside_model = result.outside_model ? 1 : 0;
    for (int a = 0; a < 3; ++a) {
      info->world_lo[a] = result.world_box.lo[a];
      info->world_hi[a] = result.world_box.hi[a];
    }
    info->tets_crossed = counters.tets_crossed;
    info->tets_visited = counters.tets_visited;
    info->shards_touched = counters.shards_touched;
    info->shard_misses = counters.shard_misses;
    info->candidates = counters.candidates;
    info->triangle_tests = counters.triangle_tests;
    info->seconds = counters.locate_seconds + counters.search_seconds + counters.shard_seconds +
                    counters.test_seconds + counters.interior_seconds;
    info->containment = int(result.containment);
    info->containing_part = result.containing_part;
    info->containing_component = result.containing_component;
  });
}

}  // extern "C"

namespace {

void copy_point(const tetrapage::geometry::Point& from, double to[3]) {
  for (int a = 0; a < 3; ++a) to[a] = from[a];
}

}  // namespace

extern "C" {

tetrapage_status tetrapage_get_contact_geometry(tetrapage_object* object, size_t contact,
                                                tetrapage_contact_geometry* geometry) {
  return guarded(__func__, [&] {
    const auto state = object_state(object);
    require(geometry, "geometry");
    *geometry = tetrapage_contact_geometry{};
    const std::size_t count = state->has_result ? state->result.contacts.size() : 0;
    if (contact >= count)
      throw tetrapage::InputError("contact " + std::to_string(contact) + " of a query with " +
                                  std::to_string(count) + " contacts");
    const tetrapage::geometry::ContactGeometry meet =
        state->flying.contact_geometry(state->result.contacts[contact]);
    geometry->shape = int(meet.shape);
    geometry->point_count = meet.count;
    for (std::uint8_t i = 0; i < meet.count; ++i) copy_point(meet.points[i], geometry->points[i]);
    copy_point(meet.first_normal, geometry->environment_normal);
    copy_point(meet.second_normal, geometry->object_normal);
  });
}

void tetrapage_distance_args_init(tetrapage_distance_args* args) {
  if (args == nullptr) return;
  *args = tetrapage_distance_args{};
  args->struct_size = sizeof(tetrapage_distance_args);
  args->max_distance = tetrapage::DistanceOptions{}.max_distance;
}

}  // extern "C"

namespace {

// tetrapage_measure_distance and the deprecated tetrapage_distance_query.
tetrapage_status measure_distance(const char* function, tetrapage_object* object,
                                  const double pose[7], const tetrapage_distance_args* args,
                                  tetrapage_distance_result* result) {
  return guarded(function, [&] {
    const auto state = object_state(object);
    state->has_result = false;
    require(pose, "pose");
    require(result, "result");
    *result = tetrapage_distance_result{};
    tetrapage_distance_args defaults;
    tetrapage_distance_args_init(&defaults);
    const tetrapage_distance_args read = read_args(args, defaults, "args");
    const tetrapage::DistanceResult found =
        state->flying.distance(pose_of(pose), tetrapage::DistanceOptions{read.max_distance});
    result->separation = int32_t(found.separation);
    result->distance = found.distance;
    result->lower_bound = found.lower_bound;
    result->upper_bound = found.upper_bound;
    copy_point(found.on_environment, result->on_environment);
    copy_point(found.on_object, result->on_object);
    result->closest = hit_of(found.closest);
    result->containment = int32_t(found.containment);
    result->containing_part = found.containing_part;
    result->containing_dynamic_part = found.containing_dynamic_part;
    result->pair_tests = found.pair_tests;
  });
}

}  // namespace

extern "C" {

void tetrapage_impact_args_init(tetrapage_impact_args* args) {
  if (args == nullptr) return;
  *args = tetrapage_impact_args{};
  args->struct_size = sizeof(tetrapage_impact_args);
  args->tolerance = tetrapage::ImpactOptions{}.tolerance;
  args->max_iterations = tetrapage::ImpactOptions{}.max_iterations;
}

}  // extern "C"

namespace {

// tetrapage_find_impact and the deprecated tetrapage_time_of_impact.
tetrapage_status find_impact(const char* function, tetrapage_object* object, const double from[7],
                             const double to[7], const tetrapage_impact_args* args,
                             tetrapage_impact_result* result) {
  return guarded(function, [&] {
    const auto state = object_state(object);
    state->has_result = false;
    require(from, "from");
    require(to, "to");
    require(result, "result");
    *result = tetrapage_impact_result{};
    tetrapage_impact_args defaults;
    tetrapage_impact_args_init(&defaults);
    const tetrapage_impact_args read = read_args(args, defaults, "args");
    if (read.max_iterations == 0 || read.max_iterations > UINT32_MAX)
      throw tetrapage::InputError("max_iterations must be in [1, 4294967295], not " +
                                  std::to_string(read.max_iterations));
    tetrapage::ImpactOptions options;
    options.tolerance = read.tolerance;
    options.max_iterations = std::uint32_t(read.max_iterations);
    const tetrapage::ImpactResult found =
        state->flying.time_of_impact(pose_of(from), pose_of(to), options);
    result->impact = int32_t(found.impact);
    result->free_until = found.free_until;
    result->contact_at = found.contact_at;
    result->first_contact = hit_of(found.contact);
    result->containment = int32_t(found.containment);
    result->containing_part = found.containing_part;
    result->containing_dynamic_part = found.containing_dynamic_part;
    result->iterations = found.iterations;
  });
}
}  // namespace

extern "C" {

tetrapage_status tetrapage_measure_distance(tetrapage_object* object, const double pose[7],
                                            const tetrapage_distance_args* args,
                                            tetrapage_distance_result* result) {
  return measure_distance(__func__, object, pose, args, result);
}

tetrapage_status tetrapage_find_impact(tetrapage_object* object, const double from[7],
                                       const double to[7], const tetrapage_impact_args* args,
                                       tetrapage_impact_result* result) {
  return find_impact(__func__, object, from, to, args, result);
}

tetrapage_status tetrapage_distance_query(tetrapage_object* object, const double pose[7],
                                          double max_distance, tetrapage_distance* result) {
  if (result) *result = tetrapage_distance{};
  tetrapage_distance_args args;
  tetrapage_distance_args_init(&args);
  args.max_distance = max_distance;
  tetrapage_distance_result found;
  const tetrapage_status status =
      measure_distance(__func__, object, pose, &args, result ? &found : nullptr);
  if (status != TETRAPAGE_OK) return status;
  // The first release's convention: part and object triangle 0 where there is no pair.
  const bool none = found.closest.environment_triangle == TETRAPAGE_NO_TRIANGLE;
  result->separation = found.separation;
  result->distance = found.distance;
  result->lower_bound = found.lower_bound;
  result->upper_bound = found.upper_bound;
  result->environment_triangle = found.closest.environment_triangle;
  result->environment_part = none ? 0 : found.closest.environment_part;
  result->object_triangle = none ? 0 : found.closest.object_triangle;
  result->containment = found.containment;
  result->containing_part = found.containing_part;
  result->pair_tests = found.pair_tests;
  std::copy(found.on_environment, found.on_environment + 3, result->on_environment);
  std::copy(found.on_object, found.on_object + 3, result->on_object);
  return status;
}

tetrapage_status tetrapage_time_of_impact(tetrapage_object* object, const double from[7],
                                          const double to[7], double tolerance,
                                          tetrapage_impact* result) {
  if (result) *result = tetrapage_impact{};
  tetrapage_impact_args args;
  tetrapage_impact_args_init(&args);
  args.tolerance = tolerance;
  tetrapage_impact_result found;
  const tetrapage_status status =
      find_impact(__func__, object, from, to, &args, result ? &found : nullptr);
  if (status != TETRAPAGE_OK) return status;
  const bool has_contact = found.first_contact.environment_triangle != TETRAPAGE_NO_TRIANGLE;
  result->impact = found.impact;
  result->free_until = found.free_until;
  result->contact_at = found.contact_at;
  result->has_contact = has_contact ? 1 : 0;
  if (has_contact) {
    result->environment_triangle = found.first_contact.environment_triangle;
    result->environment_part = found.first_contact.environment_part;
    result->object_triangle = found.first_contact.object_triangle;
  }
  result->iterations = found.iterations;
  return status;
}

}  // extern "C"
