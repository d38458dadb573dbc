#pragma once
/// @file CApiSupport.h (private)
/// What the C API's source files share (CApi.cpp, CApiGroup.cpp): the thread's last error
/// message, the handle tables (ids, never addresses), and guarded(), which turns every
/// exception into a status and a message: nothing thrown in C++ may unwind through a C
/// caller's frames. Inline, so that every file sees the one table of each kind.

#include <atomic>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <exception>
#include <memory>
#include <mutex>
#include <new>
#include <shared_mutex>
#include <string>
#include <unordered_map>
#include <utility>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/runtime/paging/CollisionIndex.h"
#include "tetrapage/runtime/query/DynamicObstacles.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/tetrapage.h"

namespace tetrapage::capi {

inline thread_local std::string last_error_message;

/// A null handle or pointer: reported as TETRAPAGE_ERROR_INVALID_ARGUMENT.
class NullArgument : public std::exception {
 public:
  explicit NullArgument(const char* name) : name_(name) {}
  const char* what() const noexcept override { return name_; }

 private:
  const char* name_;
};

template <class T>
inline void require(const T* pointer, const char* name) {
  if (pointer == nullptr) throw NullArgument(name);
}

/// An argument struct whose struct_size this library cannot read: reported as
/// TETRAPAGE_ERROR_INVALID_ARGUMENT.
class BadStructSize : public std::exception {
 public:
  explicit BadStructSize(std::string message) : message_(std::move(message)) {}
  const char* what() const noexcept override { return message_.c_str(); }

 private:
  std::string message_;
};

/// A caller's argument struct (tetrapage.h, "Argument structs"): `defaults` where `given` is
/// null, and for each field its struct_size does not cover (a program compiled against an
/// older header, whose struct ends before the fields added since).
/// @throw BadStructSize for a size below the struct_size field, or beyond this library's struct.
template <class Args>
Args read_args(const Args* given, const Args& defaults, const char* name) {
  // Fields are only ever appended, and no struct has tail padding (CApi.cpp asserts it): an
  // older struct's bytes are exactly the fields it had.
  if (given == nullptr) return defaults;
  const std::size_t size = given->struct_size;
  if (size < sizeof(std::size_t) || size > sizeof(Args))
    throw BadStructSize(std::string(name) + "->struct_size is " + std::to_string(size) +
                        ": this library reads " + std::to_string(sizeof(std::size_t)) + " to " +
                        std::to_string(sizeof(Args)) + " bytes (set it with the init function)");
  Args read = defaults;
  std::memcpy(static_cast<void*>(&read), given, size);
  read.struct_size = sizeof(Args);
  return read;
}

/// A handle that names no live index or object: reported as TETRAPAGE_ERROR_STALE_HANDLE.
class StaleHandle : public std::exception {
 public:
  explicit StaleHandle(std::string message) : message_(std::move(message)) {}
  const char* what() const noexcept override { return message_.c_str(); }

 private:
  std::string message_;
};

// What a handle stands for. The object holds the index through its FlyingObject (shared
// ownership), so closing the index handle first leaves the object answering.
struct IndexState {
  std::shared_ptr<const tetrapage::CollisionIndex> index;
};

struct ObjectState {
  tetrapage::FlyingObject flying;
  tetrapage::QueryResult result;
  bool has_result = false;
};

// Shared by every table: an index's id is never an object's or a group's.
inline std::atomic<std::uint64_t> next_handle_id{1};

/// The live handles of one kind. Lookups share the lock and return a reference-counted state,
/// so a release on another thread cannot free what a call is using.
template <class State>
class HandleTable {
 public:
  explicit HandleTable(const char* kind) : kind_(kind) {}

  std::uintptr_t add(std::shared_ptr<State> state) {
    const std::uint64_t id = next_handle_id.fetch_add(1, std::memory_order_relaxed);
    if (id > std::uint64_t(UINTPTR_MAX)) throw std::bad_alloc();  // 32-bit ids exhausted
    std::unique_lock lock(mutex_);
    live_.emplace(std::uintptr_t(id), std::move(state));
    return std::uintptr_t(id);
  }

  /// @throw StaleHandle naming the function's argument and the id.
  std::shared_ptr<State> get(std::uintptr_t id) const {
    {
      std::shared_lock lock(mutex_);
      if (auto found = live_.find(id); found != live_.end()) return found->second;
    }
    throw stale(id);
  }

  /// The state removed from the table (to be destroyed by the caller, outside the lock).
  /// @throw StaleHandle when the id is not live.
  std::shared_ptr<State> remove(std::uintptr_t id) {
    std::shared_ptr<State> removed;
    {
      std::unique_lock lock(mutex_);
      if (auto found = live_.find(id); found != live_.end()) {
        removed = std::move(found->second);
        live_.erase(found);
      }
    }
    if (!removed) throw stale(id);
    return removed;
  }

 private:
  StaleHandle stale(std::uintptr_t id) const {
    char text[160];
    std::snprintf(text, sizeof text,
                  "%s handle 0x%" PRIxPTR
                  " is stale: released already, or never returned by tetrapage",
                  kind_, id);
    return StaleHandle(text);
  }

  const char* kind_;
  mutable std::shared_mutex mutex_;
  std::unordered_map<std::uintptr_t, std::shared_ptr<State>> live_;
};

// Never destroyed: a caller may release handles from its own static destructors, and the
// states of handles never released must not be torn down (with their threads) at exit.
inline HandleTable<IndexState>& indexes() {
  static auto* table = new HandleTable<IndexState>("index");
  return *table;
}

inline HandleTable<ObjectState>& objects() {
  static auto* table = new HandleTable<ObjectState>("object");
  return *table;
}

inline std::uintptr_t id_of(const void* handle) {
  return reinterpret_cast<std::uintptr_t>(handle);
}

inline std::shared_ptr<IndexState> index_state(const tetrapage_index* index) {
  require(index, "index");
  return indexes().get(id_of(index));
}

inline std::shared_ptr<ObjectState> object_state(const tetrapage_object* object) {
  require(object, "object");
  return objects().get(id_of(object));
}

inline tetrapage_status fail(tetrapage_status status, const char* function,
                             const char* what) noexcept {
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
inline tetrapage_status guarded(const char* function, Body&& body) noexcept {
  try {
    body();
    last_error_message.clear();
    return TETRAPAGE_OK;
  } catch (const NullArgument& e) {
    return fail(TETRAPAGE_ERROR_INVALID_ARGUMENT, function,
                (std::string(e.what()) + " is null").c_str());
  } catch (const BadStructSize& e) {
    return fail(TETRAPAGE_ERROR_INVALID_ARGUMENT, function, e.what());
  } catch (const StaleHandle& e) {
    return fail(TETRAPAGE_ERROR_STALE_HANDLE, function, e.what());
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

/// A mesh from the C arrays (vertices: 3 doubles each; triangles: 3 vertex indices each).
/// @throw InputError for a vertex index out of range, naming the triangle.
inline tetrapage::TriangleSoup object_soup(const double* vertices, std::size_t vertex_count,
                                           const std::uint32_t* triangles,
                                           std::size_t triangle_count) {
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

/// The overlay of an obstacles handle, for the objects and groups that attach it (null for a
/// null handle). Defined in CApiObstacles.cpp, with its table.
/// @throw StaleHandle for a destroyed or foreign handle.
std::shared_ptr<const tetrapage::DynamicObstacles> obstacles_of(
    const tetrapage_obstacles* obstacles);

/// The int a C caller passed as an enum, read without loading it as the C++ enum: any int may
/// arrive, and loading one outside the enumerators' range is undefined behaviour in C++.
/// (Even copying it is such a load, so the enum is taken by reference.)
template <class Enum>
inline int caller_value(const Enum& value) {
  static_assert(sizeof(Enum) == sizeof(int));
  int raw = 0;
  std::memcpy(&raw, &value, sizeof raw);
  return raw;
}

}  // namespace tetrapage::capi
