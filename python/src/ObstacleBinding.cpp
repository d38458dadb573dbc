// tetrapage.Obstacles: parts inserted, moved and removed between steps, and index parts hidden.

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "Bindings.h"
#include "tetrapage/formats/base/Error.h"

namespace tetrapage::python {

namespace {

// A change takes the overlay exclusively: no step of an object holding it runs meanwhile.
template <class Change>
auto change(Obstacles& obstacles, Change&& apply) {
  StepLocks::refuse_held(obstacles.lock.get(), "obstacles");
  py::gil_scoped_release unlocked;
  std::unique_lock exclusive(*obstacles.lock);
  return apply(*obstacles.overlay);
}

Obstacles obstacles_of(DynamicObstacles overlay) {
  Obstacles obstacles;
  obstacles.overlay = std::make_shared<DynamicObstacles>(std::move(overlay));
  return obstacles;
}

// A read shares the overlay, the GIL released first: a thread that holds the overlay in a step
// may need the GIL (to check for Ctrl-C) before it lets go.
template <class Read>
auto read(const Obstacles& obstacles, Read&& look) {
  py::gil_scoped_release unlocked;
  // A step of this thread (which ran a signal handler) may already share it.
  std::shared_lock shared(*obstacles.lock, std::defer_lock);
  if (!StepLocks::held(obstacles.lock.get())) shared.lock();
  return look(static_cast<const DynamicObstacles&>(*obstacles.overlay));
}

}  // namespace

HeldOverlay overlay_of(py::handle value) {
  if (value.is_none()) return {};
  if (!py::isinstance<Obstacles>(value))
    throw InputError("obstacles: a tetrapage.Obstacles or None is expected");
  const Obstacles& obstacles = value.cast<const Obstacles&>();
  return {obstacles.overlay, obstacles.lock};
}

void bind_obstacles(py::module_& module) {
  py::class_<Obstacles>(module, "Obstacles", R"(Obstacles that change between steps, merged into the
queries of every object that holds them (FlyingObject.obstacles = ...): parts inserted, moved
and removed, and parts of the index hidden. Changes wait for the steps in progress on other
threads and hold them off while they run.)")
      .def(py::init([](const Index& index, double cell_size) {
             return obstacles_of(DynamicObstacles(index.index, cell_size));
           }),
           py::arg("index"), py::kw_only(), py::arg("cell_size") = 0.0,
           "An empty overlay on `index` (cell_size 0: 1/64 of the model's longest side).")
      .def(
          "insert",
          [](Obstacles& obstacles, py::handle mesh, py::handle pose_value, std::string name) {
            const Pose pose = pose_from_array(pose_value, "pose");
            // Built before the overlay is taken: steps wait only for the insertion.
            std::shared_ptr<const ObjectModel> model = model_of(mesh, py::none(), "mesh");
            return change(obstacles, [&](DynamicObstacles& overlay) {
              return overlay.insert(std::move(model), pose, std::move(name));
            });
          },
          py::arg("mesh"), py::arg("pose"), py::arg("name") = "",
          "Adds a part (a Model, shared at no cost; a Mesh or a (vertices, triangles) pair) at "
          "`pose`; returns its id (> 0), "
          "the `dynamic_part` of its contacts.")
      .def(
          "move",
          [](Obstacles& obstacles, py::handle id_value, py::handle pose_value) {
            const auto id = DynamicPartId(whole_number(id_value, "id", 0, 0xffffffffu));
            const Pose pose = pose_from_array(pose_value, "pose");
            change(obstacles, [&](DynamicObstacles& overlay) { overlay.move(id, pose); });
          },
          py::arg("id"), py::arg("pose"),
          "Puts the inserted part `id` at `pose` (where it now stands, not a displacement); "
          "raises InputError for an unknown id.")
      .def(
          "remove",
          [](Obstacles& obstacles, py::handle id_value) {
            const auto id = DynamicPartId(whole_number(id_value, "id", 0, 0xffffffffu));
            change(obstacles, [&](DynamicObstacles& overlay) { overlay.remove(id); });
          },
          py::arg("id"),
          "Removes the inserted part `id` (its id is never given again); raises InputError "
          "for an unknown id.")
      .def(
          "hide_part",
          [](Obstacles& obstacles, py::handle part_value) {
            const auto part = std::uint32_t(whole_number(part_value, "part", 0, 0xffffffffu));
            change(obstacles, [&](DynamicObstacles& overlay) { overlay.hide_part(part); });
          },
          py::arg("part"), "Hides a part of the index (its id in Index.parts) from every answer.")
      .def(
          "show_part",
          [](Obstacles& obstacles, py::handle part_value) {
            const auto part = std::uint32_t(whole_number(part_value, "part", 0, 0xffffffffu));
            change(obstacles, [&](DynamicObstacles& overlay) { overlay.show_part(part); });
          },
          py::arg("part"),
          "Shows again a part of the index (its id in Index.parts) that hide_part hid (a part "
          "not hidden stays shown); raises InputError for a part the index does not list.")
      .def_property_readonly(
          "hidden_parts",
          [](const Obstacles& o) {
            return read(o, [](const DynamicObstacles& overlay) { return overlay.hidden_parts(); });
          },
          "The ids (in Index.parts) of the index's parts hidden by hide_part, ascending.")
      .def_property_readonly(
          "parts",
          [](const Obstacles& o) {
            return read(o, [](const DynamicObstacles& overlay) {
              std::vector<std::pair<DynamicPartId, std::string>> parts;
              for (const auto& part : overlay.parts()) parts.emplace_back(part.id, part.name);
              std::sort(parts.begin(), parts.end());
              return parts;
            });
          },
          "(id, name) of every inserted part, by id.")
      .def("__len__",
           [](const Obstacles& o) {
             return read(o, [](const DynamicObstacles& overlay) { return overlay.size(); });
           })
      .def(
          "save",
          [](const Obstacles& obstacles, const std::filesystem::path& path) {
            read(obstacles, [&](const DynamicObstacles& overlay) { overlay.save(path); });
          },
          py::arg("path"),
          "Writes the overlay as text (coordinates exactly), for `fly --obstacles`.")
      .def_static(
          "load",
          [](const Index& index, const std::filesystem::path& path, double cell_size) {
            py::gil_scoped_release unlocked;
            return obstacles_of(DynamicObstacles::load(index.index, path, cell_size));
          },
          py::arg("index"), py::arg("path"), py::kw_only(), py::arg("cell_size") = 0.0,
          "An overlay on `index` read from a file that save() wrote: the same ids, names, "
          "poses, meshes and hidden parts (cell_size as for Obstacles()). Raises FormatError "
          "for a missing, truncated or malformed file (naming the line at fault) or one that "
          "does not fit `index`, IoError for a path that is not a regular file.");
}

}  // namespace tetrapage::python
