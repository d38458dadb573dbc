#pragma once
// What the binding files share: the wrappers that own the C++ objects, the conversions between
// numpy arrays and tetrapage's types, and one bind_* function per concept (Module.cpp calls them).

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <mutex>
#include <shared_mutex>
#include <string>
#include <string_view>
#include <vector>

#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/runtime/paging/CollisionIndex.h"
#include "tetrapage/runtime/query/DynamicObstacles.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/runtime/query/ObjectModel.h"

namespace tetrapage::python {

namespace py = pybind11;

/// A mesh as Python sees it: the soup and the unit its file stated.
struct Mesh {
  TriangleSoup soup;
  std::string length_unit;
};

/// An opened index (shared by every object made from it, on any thread).
struct Index {
  std::shared_ptr<const CollisionIndex> index;
};

/// A dynamic-obstacle overlay. Changes take the lock exclusively, queries of the objects that
/// hold the overlay share it: Python threads may change it while others fly (the C++ overlay
/// asks its caller to keep changes and steps apart).
struct Obstacles {
  std::shared_ptr<DynamicObstacles> overlay;
  std::shared_ptr<std::shared_mutex> lock = std::make_shared<std::shared_mutex>();
};

/// Poses read from a (7,), (K,7), (4,4) or (K,4,4) array: whether it held one pose.
struct PoseBatch {
  std::vector<Pose> poses;
  bool single = false;
};

/// @throw InputError naming `what` for a wrong dtype or shape, a matrix that is not a rigid
///        motion (rotation block not orthonormal with determinant +1, last row not 0 0 0 1).
PoseBatch poses_from_array(py::handle value, std::string_view what);
/// Any array-like as a numpy array.
/// @throw InputError naming `what` for what numpy cannot read as an array (a ragged list).
py::array as_array(py::handle value, std::string_view what);
/// Exactly one pose.
Pose pose_from_array(py::handle value, std::string_view what);
/// A soup of one part from (N,3) vertices (floating or integer) and (M,3) integer triangles.
/// @throw InputError naming the array and the entry for a wrong dtype or shape, a negative or
///        out-of-range index.
TriangleSoup soup_from_arrays(py::handle vertices, py::handle triangles);
/// A Mesh, or a (vertices, triangles) pair.
TriangleSoup soup_from_mesh_like(py::handle value, std::string_view what);
/// A float64 array of the given shape holding `values` (copied).
py::array_t<double> double_array(const double* values, std::vector<py::ssize_t> shape);
/// A (2,3) array: the box's lo and hi rows.
py::array_t<double> box_array(const Vec3& lo, const Vec3& hi);
/// A Python int in [lowest, highest] (compared as Python ints, so 2**70 or -1 is named, not cast).
/// @throw InputError naming `what` and the value otherwise (a bool or a float too).
std::uint64_t whole_number(py::handle value, const char* what, std::uint64_t lowest,
                           std::uint64_t highest);
/// A memory budget: None (the library's default), a byte count, or a size text ("256M").
std::uint64_t memory_bytes(py::handle value, std::uint64_t default_bytes);

void bind_errors(py::module_& module);
void bind_meshes(py::module_& module);
void bind_preprocess(py::module_& module);
void bind_index(py::module_& module);
void bind_objects(py::module_& module);
void bind_groups(py::module_& module);
void bind_obstacles(py::module_& module);

}  // namespace tetrapage::python

namespace tetrapage::python {

/// The locks of one step, taken with the GIL released: its holder's (one thread at a time) and
/// its overlay's, shared (no change meanwhile). A step's Ctrl-C check runs Python signal handlers
/// on the step's thread with them held: a handler that steps the same holder or changes the
/// overlay gets an InputError rather than waiting forever for its own thread, and one that steps
/// another holder of the overlay uses the shared lock its thread already holds.
class StepLocks {
 public:
  /// @throw InputError if this thread's steps hold `busy`.
  StepLocks(std::mutex& busy, const std::shared_ptr<std::shared_mutex>& overlay);
  ~StepLocks();
  StepLocks(const StepLocks&) = delete;
  StepLocks& operator=(const StepLocks&) = delete;

  /// Whether a step of this thread holds `lock`.
  static bool held(const void* lock);
  /// @throw InputError naming `what` if a step of this thread holds `lock`.
  static void refuse_held(const void* lock, const std::string& what);

 private:
  std::unique_lock<std::mutex> busy_;
  std::shared_lock<std::shared_mutex> overlay_;
};

/// A flying object as Python holds it: used by one thread at a time (a second thread waits), with
/// the overlay it reads, if any.
struct Object {
  std::unique_ptr<FlyingObject> flying;
  std::unique_ptr<std::mutex> busy = std::make_unique<std::mutex>();
  std::shared_ptr<std::shared_mutex> obstacles_lock;  ///< the overlay's, or null
  py::object obstacles = py::none();                  ///< the Obstacles it holds, or None
};

/// An object's model, immutable: shared by any number of objects, obstacles and threads.
struct Model {
  std::shared_ptr<const ObjectModel> model;
};

/// A Model's own model, or one built (the GIL released) from a Mesh, a (vertices, triangles)
/// pair, or `mesh` as vertices with `triangles`.
/// @throw InputError naming `what` for anything else, and what ObjectModel throws.
std::shared_ptr<const ObjectModel> model_of(py::handle mesh, py::handle triangles,
                                            std::string_view what);

/// An object of `mesh` (a Model, a Mesh or a (vertices, triangles) pair) flying through `index`.
Object make_object(const Index& index, py::handle mesh, py::handle triangles);

/// Query options from their names, as keyword arguments give them.
/// @throw InputError naming the argument and the values it takes.
QueryOptions query_options(const std::string& mode, const std::string& accuracy,
                           const std::string& shape, const std::string& motion);

/// One python-side dict of a step's counters.
py::dict counters_dict(const StepCounters& counters);

}  // namespace tetrapage::python

namespace tetrapage::python {

/// The overlay of an Obstacles and its lock, or nulls for None.
/// @throw InputError for anything else.
struct HeldOverlay {
  std::shared_ptr<const DynamicObstacles> overlay;
  std::shared_ptr<std::shared_mutex> lock;
};
HeldOverlay overlay_of(py::handle obstacles);

/// Gives `holder` (a wrapper with busy, obstacles_lock and obstacles, as Object) the overlay
/// `value` (an Obstacles, or None for none), set on its C++ `runtime` between its steps.
/// @throw InputError for anything else, or an overlay on another index.
template <class Holder, class Runtime>
void hold_obstacles(Holder& holder, Runtime& runtime, py::handle value) {
  auto [overlay, lock] = overlay_of(value);
  StepLocks::refuse_held(holder.busy.get(), "obstacles");
  {
    py::gil_scoped_release unlocked;
    std::lock_guard busy(*holder.busy);
    runtime.set_obstacles(overlay);
    holder.obstacles_lock = lock;
  }
  holder.obstacles = py::reinterpret_borrow<py::object>(value);
}

}  // namespace tetrapage::python
