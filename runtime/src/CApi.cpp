// The C API (tetrapage.h) over CollisionIndex and FlyingObject. Every entry point runs its
// body inside guarded(), which turns every exception into a status and a thread-local message:
// nothing thrown in C++ may unwind through a C caller's frames.

#include "tetrapage/tetrapage.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <memory>
#include <new>
#include <string>
#include <utility>

#include "tetrapage/formats/Error.h"
#include "tetrapage/formats/MeshReader.h"
#include "tetrapage/runtime/CollisionIndex.h"
#include "tetrapage/runtime/FlyingObject.h"
#include "tetrapage/runtime/geometry/Accuracy.h"

struct tetrapage_index {
  // Shared with the objects, so that closing the handle before them is safe.
  std::shared_ptr<const tetrapage::CollisionIndex> index;
};

struct tetrapage_object {
  tetrapage::FlyingObject flying;
  tetrapage::QueryResult result;
  bool has_result = false;
};

namespace {

thread_local std::string last_error_message;

/// A null handle or pointer: reported as TETRAPAGE_ERROR_INVALID_ARGUMENT.
class NullArgument : public std::exception {
 public:
  explicit NullArgument(const char* name) : name_(name) {}
  const char* what() const noexcept override { return name_; }

 private:
  const char* name_;
};

template <class T>
void require(const T* pointer, const char* name) {
  if (pointer == nullptr) throw NullArgument(name);
}

tetrapage_status fail(tetrapage_status status, const char* function, const char* what) noexcept {
  try {
    last_error_message = std::string(function) + ": " + what;
  } catch (...) {
    // No memory for the message: the status still says what happened.
    last_error_message.clear();
  }
  return status;
}

/// Runs `body`, mapping each exception to its status (most derived first).
template <class Body>
tetrapage_status guarded(const char* function, Body&& body) noexcept {
  try {
    body();
    last_error_message.clear();
    return TETRAPAGE_OK;
  } catch (const NullArgument& e) {
    return fail(TETRAPAGE_ERROR_INVALID_ARGUMENT, function,
                (std::string(e.what()) + " is null").c_str());
  } catch (const tetrapage::IoError& e) {
    return fail(TETRAPAGE_ERROR_IO, function, e.what());
  } catch (const tetrapage::FormatError& e) {
    return fail(TETRAPAGE_ERROR_FORMAT, function, e.what());
  } catch (const tetrapage::InputError& e) {
    return fail(TETRAPAGE_ERROR_INPUT, function, e.what());
  } catch (const std::bad_alloc&) {
    return fail(TETRAPAGE_ERROR_OUT_OF_MEMORY, function, "out of memory");
  } catch (const std::exception& e) {
    return fail(TETRAPAGE_ERROR_INTERNAL, function, e.what());
  } catch (...) {
    return fail(TETRAPAGE_ERROR_INTERNAL, function, "unknown exception");
  }
}

tetrapage::geometry::Accuracy to_accuracy(tetrapage_accuracy accuracy, double parameter) {
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
  throw tetrapage::InputError("unknown accuracy " + std::to_string(int(accuracy)));
}

tetrapage::TriangleSoup object_soup(const double* vertices, std::size_t vertex_count,
                                    const std::uint32_t* triangles, std::size_t triangle_count) {
  tetrapage::TriangleSoup soup;
  soup.vertices.resize(vertex_count);
  for (std::size_t v = 0; v < vertex_count; ++v)
    soup.vertices[v] = {vertices[3 * v], vertices[3 * v + 1], vertices[3 * v + 2]};
  soup.triangles.resize(triangle_count);
  for (std::size_t t = 0; t < triangle_count; ++t) {
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t vertex = triangles[3 * t + c];
      // FlyingObject checks too; saying it here names the C arrays.
      if (vertex >= vertex_count)
        throw tetrapage::InputError("triangle " + std::to_string(t) + " refers to vertex " +
                                    std::to_string(vertex) + " but there are " +
                                    std::to_string(vertex_count) + " vertices");
      soup.triangles[t][c] = vertex;
    }
  }
  soup.part_of.assign(triangle_count, 0);
  soup.part_names = {"object"};
  return soup;
}

}  // namespace

extern "C" {

const char* tetrapage_last_error(void) { return last_error_message.c_str(); }

const char* tetrapage_status_string(tetrapage_status status) {
  switch (status) {
    case TETRAPAGE_OK: return "ok";
    case TETRAPAGE_ERROR_IO: return "I/O error";
    case TETRAPAGE_ERROR_FORMAT: return "format error";
    case TETRAPAGE_ERROR_INPUT: return "input error";
    case TETRAPAGE_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case TETRAPAGE_ERROR_OUT_OF_MEMORY: return "out of memory";
    case TETRAPAGE_ERROR_INTERNAL: return "internal error";
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
    auto opened = std::make_unique<tetrapage_index>();
    opened->index = std::make_shared<const tetrapage::CollisionIndex>(path, options);
    *index = opened.release();
  });
}

void tetrapage_close(tetrapage_index* index) {
  // Releasing only drops references and frees memory: nothing can throw here.
  delete index;
}

tetrapage_status tetrapage_index_bounds(const tetrapage_index* index, double lo[3], double hi[3]) {
  return guarded(__func__, [&] {
    require(index, "index");
    require(lo, "lo");
    require(hi, "hi");
    const auto& bounds = index->index->header().bounds;
    for (int a = 0; a < 3; ++a) {
      lo[a] = bounds.lo[a];
      hi[a] = bounds.hi[a];
    }
  });
}

tetrapage_status tetrapage_object_create(tetrapage_index* index, const double* vertices,
                                         size_t vertex_count, const uint32_t* triangles,
                                         size_t triangle_count, tetrapage_object** object) {
  if (object) *object = nullptr;
  return guarded(__func__, [&] {
    require(index, "index");
    require(object, "object");
    if (vertex_count > 0) require(vertices, "vertices");
    if (triangle_count > 0) require(triangles, "triangles");
    auto soup = object_soup(vertices, vertex_count, triangles, triangle_count);
    auto created = std::make_unique<tetrapage_object>(
        tetrapage_object{tetrapage::FlyingObject(index->index, std::move(soup)), {}, false});
    *object = created.release();
  });
}

tetrapage_status tetrapage_object_create_from_file(tetrapage_index* index, const char* path,
                                                   tetrapage_object** object) {
  if (object) *object = nullptr;
  return guarded(__func__, [&] {
    require(index, "index");
    require(path, "path");
    require(object, "object");
    auto created = std::make_unique<tetrapage_object>(
        tetrapage_object{tetrapage::FlyingObject(index->index, tetrapage::read_mesh(path)), {}, false});
    *object = created.release();
  });
}

void tetrapage_object_destroy(tetrapage_object* object) { delete object; }

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

tetrapage_status tetrapage_query(tetrapage_object* object, const double pose[7],
                                 tetrapage_accuracy accuracy, double parameter, int all_contacts,
                                 int* collides) {
  return tetrapage_query_shaped(object, pose, accuracy, parameter, TETRAPAGE_SHAPE_MESH,
                                TETRAPAGE_MOTION_DISCRETE, all_contacts, collides);
}

tetrapage_status tetrapage_query_shaped(tetrapage_object* object, const double pose[7],
                                        tetrapage_accuracy accuracy, double parameter,
                                        tetrapage_object_shape shape, tetrapage_motion motion,
                                        int all_contacts, int* collides) {
  if (collides) *collides = 0;
  if (object) object->has_result = false;
  return guarded(__func__, [&] {
    require(object, "object");
    require(pose, "pose");
    require(collides, "collides");
    tetrapage::QueryOptions options;
    options.accuracy = to_accuracy(accuracy, parameter);
    switch (shape) {
      case TETRAPAGE_SHAPE_MESH: options.shape = tetrapage::ObjectShape::mesh; break;
      case TETRAPAGE_SHAPE_HULL: options.shape = tetrapage::ObjectShape::hull; break;
      case TETRAPAGE_SHAPE_BOX: options.shape = tetrapage::ObjectShape::box; break;
      default: throw tetrapage::InputError("unknown object shape " + std::to_string(int(shape)));
    }
    switch (motion) {
      case TETRAPAGE_MOTION_DISCRETE: options.motion = tetrapage::Motion::discrete; break;
      case TETRAPAGE_MOTION_SWEPT: options.motion = tetrapage::Motion::swept; break;
      default: throw tetrapage::InputError("unknown motion " + std::to_string(int(motion)));
    }
    options.mode = all_contacts ? tetrapage::QueryMode::all_contacts : tetrapage::QueryMode::first_hit;
    tetrapage::Pose placed;
    placed.translation = {pose[0], pose[1], pose[2]};
    placed.rotation = {pose[3], pose[4], pose[5], pose[6]};
    object->flying.query(placed, options, object->result);
    object->has_result = true;
    *collides = object->result.collides ? 1 : 0;
  });
}

tetrapage_status tetrapage_contact_count(const tetrapage_object* object, size_t* count) {
  if (count) *count = 0;
  return guarded(__func__, [&] {
    require(object, "object");
    require(count, "count");
    *count = object->has_result ? object->result.contacts.size() : 0;
  });
}

tetrapage_status tetrapage_get_contacts(const tetrapage_object* object,
                                        tetrapage_contact* contacts, size_t capacity,
                                        size_t* written) {
  if (written) *written = 0;
  return guarded(__func__, [&] {
    require(object, "object");
    require(written, "written");
    if (capacity > 0) require(contacts, "contacts");
    if (!object->has_result) return;
    const auto& found = object->result.contacts;
    const std::size_t n = std::min(capacity, found.size());
    for (std::size_t i = 0; i < n; ++i)
      contacts[i] = {found[i].environment_triangle, found[i].environment_part, found[i].object_triangle,
                     found[i].environment_component};
    *written = n;
  });
}

tetrapage_status tetrapage_last_query_info(const tetrapage_object* object,
                                           tetrapage_query_info* info) {
  return guarded(__func__, [&] {
    require(object, "object");
    require(info, "info");
    *info = tetrapage_query_info{};
    if (!object->has_result) return;
    const auto& result = object->result;
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
