// tetrapage.ObjectGroup: several objects stepped together, each against the environment and
// every pair against each other.

#include <pybind11/stl.h>

#include "Bindings.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/runtime/query/ObjectGroup.h"

namespace tetrapage::python {

namespace {

struct PairRecord {
  std::uint32_t first;
  std::uint32_t second;
  std::uint8_t
      containment;  // 0 none (surfaces touch), 1 first inside second, 2 second inside first
  std::uint32_t triangle_pairs_begin;
  std::uint32_t triangle_pairs_end;
};

struct Group {
  std::unique_ptr<ObjectGroup> group;
  std::unique_ptr<std::mutex> busy = std::make_unique<std::mutex>();
  std::shared_ptr<std::shared_mutex> obstacles_lock;
  py::object obstacles = py::none();
};

struct GroupAnswer {
  py::object environment, pairs, triangle_pairs, world_boxes;
};

Group make_group(py::handle objects, py::handle index) {
  std::vector<std::shared_ptr<const ObjectModel>> models;
  for (py::handle object : objects) models.push_back(model_of(object, py::none(), "objects"));
  std::shared_ptr<const CollisionIndex> environment;
  if (!index.is_none()) {
    if (!py::isinstance<Index>(index))
      throw InputError("index: a tetrapage.Index or None is expected");
    environment = index.cast<const Index&>().index;
  }
  // Made with the GIL held: its `obstacles` takes a reference to None, and drops it if the
  // group's construction throws.
  Group group;
  py::gil_scoped_release unlocked;
  group.group = std::make_unique<ObjectGroup>(environment, std::move(models));
  return group;
}

GroupAnswer step(Group& group, py::handle poses, bool environment, bool pairs,
                 const std::string& pair_mode, bool containment, bool parallel,
                 const std::string& accuracy, const std::string& shape, const std::string& motion) {
  const PoseBatch batch = poses_from_array(poses, "poses");
  GroupQueryOptions options;
  options.check_environment = environment && group.group->index();
  options.environment = query_options("first_hit", accuracy, shape, motion);
  options.check_pairs = pairs;
  options.pair_mode = query_options(pair_mode, "exact", "mesh", "discrete").mode;
  options.pair_containment = containment;
  options.parallel = parallel;
  GroupResult result;
  {
    py::gil_scoped_release unlocked;
    const StepLocks locks(*group.busy, group.obstacles_lock);
    group.group->step(batch.poses, options, result);
  }
  GroupAnswer answer;
  py::array_t<bool> collides(py::ssize_t(result.environment.size()));
  for (std::size_t i = 0; i < result.environment.size(); ++i)
    collides.mutable_at(py::ssize_t(i)) = result.environment[i].collides;
  answer.environment = collides;
  std::vector<PairRecord> records;
  for (const CollidingPair& p : result.pairs)
    records.push_back({p.first, p.second, std::uint8_t(p.containment), p.triangle_pairs_begin,
                       p.triangle_pairs_end});
  answer.pairs = py::array_t<PairRecord>(py::ssize_t(records.size()), records.data());
  py::array_t<std::uint32_t> triangles({py::ssize_t(result.triangle_pairs.size()), py::ssize_t(2)});
  for (std::size_t i = 0; i < result.triangle_pairs.size(); ++i) {
    triangles.mutable_at(py::ssize_t(i), 0) = result.triangle_pairs[i].first_triangle;
    triangles.mutable_at(py::ssize_t(i), 1) = result.triangle_pairs[i].second_triangle;
  }
  answer.triangle_pairs = triangles;
  py::array_t<double> boxes(
      {py::ssize_t(result.world_boxes.size()), py::ssize_t(2), py::ssize_t(3)});
  for (std::size_t i = 0; i < result.world_boxes.size(); ++i)
    for (int a = 0; a < 3; ++a) {
      boxes.mutable_at(py::ssize_t(i), 0, a) = result.world_boxes[i].lo[a];
      boxes.mutable_at(py::ssize_t(i), 1, a) = result.world_boxes[i].hi[a];
    }
  answer.world_boxes = boxes;
  return answer;
}

}  // namespace

void bind_groups(py::module_& module) {
  PYBIND11_NUMPY_DTYPE(PairRecord, first, second, containment, triangle_pairs_begin,
                       triangle_pairs_end);
  py::class_<GroupAnswer>(module, "GroupAnswer", R"(One step of an ObjectGroup.
environment: (N,) bool, each object against the environment (empty without an index).
pairs: structured array of the colliding pairs (first < second, sorted): containment 0 when
  surfaces touch, 1 when first lies inside second, 2 the reverse; their triangle pairs are
  triangle_pairs[triangle_pairs_begin:triangle_pairs_end].
triangle_pairs: (P, 2) uint32, a triangle of the pair's first object and one of its second.
world_boxes: (N, 2, 3).)")
      .def_readonly("environment", &GroupAnswer::environment,
                    "(N,) bool: whether object i collides with the environment (the index and "
                    "the obstacles) at poses[i]; empty without an index or with "
                    "environment=False.")
      .def_readonly("pairs", &GroupAnswer::pairs,
                    "The colliding pairs of objects, a structured array sorted by (first, "
                    "second): first, second (indices in the group, first < second), "
                    "containment, triangle_pairs_begin, triangle_pairs_end.")
      .def_readonly("triangle_pairs", &GroupAnswer::triangle_pairs,
                    "(P, 2) uint32: per row, a triangle of a pair's first object (its row in "
                    "that object's triangles) that meets one of its second (pair_mode "
                    "\"first_hit\": one row per pair; a containment has none).")
      .def_readonly("world_boxes", &GroupAnswer::world_boxes,
                    "(N, 2, 3): each object's world box at its pose (lowest and highest "
                    "corner), in world coordinates.");

  py::class_<Group>(module, "ObjectGroup", R"(Several rigid objects moving together through one
index (or none: object/object questions only). Object/object answers are always exact.)")
      .def(py::init(&make_group), py::arg("objects"), py::arg("index") = py::none(),
           "objects: a list of Model, Mesh or (vertices, triangles) pairs.")
      .def("step", &step, py::arg("poses"), py::kw_only(), py::arg("environment") = true,
           py::arg("pairs") = true, py::arg("pair_mode") = "first_hit",
           py::arg("containment") = true, py::arg("parallel") = false,
           py::arg("accuracy") = "exact", py::arg("shape") = "mesh", py::arg("motion") = "discrete",
           "One step: object i at poses[i] ((N, 7) or (N, 4, 4)). parallel: the environment "
           "queries on TBB's threads. Returns a GroupAnswer.")
      .def(
          "set_obstacles",
          [](Group& group, py::handle value) { hold_obstacles(group, *group.group, value); },
          py::arg("obstacles"), "Obstacles merged into every object's environment query, or None.")
      .def("__len__", [](const Group& g) { return g.group->size(); });
}

}  // namespace tetrapage::python
