// tetrapage.Index: an opened index, what `tetrapage inspect` tells about it, and the objects that
// fly through it.

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "Bindings.h"
#include "tetrapage/formats/index/IndexReader.h"
#include "tetrapage/formats/index/IndexSummary.h"

namespace tetrapage::python {

namespace {

struct Part {
  std::uint32_t id = 0;
  std::string name, path;
  std::uint64_t triangles = 0;
};

std::vector<Part> parts_of(const CollisionIndex& index) {
  std::vector<Part> parts;
  for (std::uint32_t p = 0; p < index.parts().count(); ++p)
    parts.push_back({p, index.parts().name(p), index.parts().path(p), index.parts().triangles(p)});
  return parts;
}

py::array_t<std::uint64_t> shard_bytes_of(const CollisionIndex& index) {
  py::array_t<std::uint64_t> bytes(py::ssize_t(index.shard_count()));
  for (std::uint32_t s = 0; s < index.shard_count(); ++s)
    bytes.mutable_at(s) = index.shard_bytes(s);
  return bytes;
}

Index open_index(const std::filesystem::path& path, py::handle memory, bool prefetch) {
  CollisionIndexOptions options;
  options.memory_budget_bytes = memory_bytes(memory, options.memory_budget_bytes);
  options.prefetch = prefetch;
  py::gil_scoped_release unlocked;
  return Index{std::make_shared<const CollisionIndex>(path, options)};
}

py::dict inspect(const Index& self) {
  // The summary `tetrapage inspect --report` writes (read from a reader of its own: the
  // index's serves its shard cache), and what this opening of the index adds.
  std::string summary;
  {
    py::gil_scoped_release unlocked;
    summary = IndexSummary::of(IndexReader(self.index->path())).to_json();
  }
  py::dict info = py::module_::import("json").attr("loads")(summary);
  info["memory_budget_bytes"] = self.index->options().memory_budget_bytes;
  return info;
}

}  // namespace

void bind_index(py::module_& module) {
  py::class_<Part>(module, "Part", "A part of an indexed model (a contact's `part` is its id).")
      .def_readonly("id", &Part::id,
                    "Its number, its position in Index.parts: a contact's `part`, an answer's "
                    "environment_part, what Obstacles.hide_part takes.")
      .def_readonly("name", &Part::name, "What the file calls the part.")
      .def_readonly("path", &Part::path, "Its instance path in the assembly, unique in the model.")
      .def_readonly("triangles", &Part::triangles,
                    "Triangles it holds in the index (0: not recorded).")
      .def("__repr__", [](const Part& p) {
        return "<tetrapage.Part " + std::to_string(p.id) + " '" + p.path + "', " +
               std::to_string(p.triangles) + " triangles>";
      });

  py::class_<Index>(module, "Index", R"(An index opened for queries. Shards are paged in on demand
within `memory` (bytes, or a size such as "256M": k, M, G, T are powers of 1024; None: the
shared default, tetrapage.DEFAULT_MEMORY (1 GiB)); the budget is never exceeded. Any number of objects, each used from its own
thread, may share one Index.)")
      .def(py::init(&open_index), py::arg("path"), py::kw_only(), py::arg("memory") = py::none(),
           py::arg("prefetch") = true,
           "Opens and checks the index. Raises IoError, FormatError (not an index, damaged), "
           "InputError (a budget smaller than the largest shard).")
      .def_property_readonly(
          "path", [](const Index& i) { return i.index->path(); },
          "The index file it was opened from, as a pathlib.Path.")
      .def_property_readonly(
          "bounds",
          [](const Index& i) {
            const BoundingBox& box = i.index->header().bounds;
            return box_array(box.lo, box.hi);
          },
          "(2, 3): the model's lowest and highest corner.")
      .def_property_readonly(
          "length_unit", [](const Index& i) { return i.index->header().length_unit; },
          "The model's unit (\"mm\", \"m\"), or \"\" when no input said.")
      .def_property_readonly(
          "precision", [](const Index& i) { return i.index->header().precision; },
          "How coordinates are stored: \"exact\", \"double\" or \"float\".")
      .def_property_readonly(
          "parts", [](const Index& i) { return parts_of(*i.index); }, "The model's parts, by id.")
      .def_property_readonly(
          "triangles", [](const Index& i) { return i.index->header().input_triangles; },
          "How many triangles the model holds: those read from the inputs, every placed "
          "instance counted and degenerate ones dropped (the triangles' ids run below it).")
      .def_property_readonly(
          "shard_bytes", [](const Index& i) { return shard_bytes_of(*i.index); },
          "(S,) uint64: each shard's decoded bytes (what it costs resident).")
      .def_property_readonly(
          "total_shard_bytes", [](const Index& i) { return i.index->total_shard_bytes(); },
          "The sum of shard_bytes: what every shard resident costs, in bytes (preload() needs "
          "a memory budget at least this large).")
      .def_property_readonly(
          "memory", [](const Index& i) { return i.index->options().memory_budget_bytes; },
          "The shard budget in bytes.")
      .def_property_readonly(
          "has_interiors", [](const Index& i) { return i.index->has_interiors(); },
          "Whether containment (an object inside a closed part) is answered.")
      .def("object", &make_object, py::arg("mesh"), py::arg("triangles") = py::none(),
           R"(A FlyingObject: object(model) with a tetrapage.Model (immediate), object(mesh) with a
tetrapage.Mesh, or object(vertices, triangles) with an (N, 3) float array and an (M, 3) integer
array, in the index's coordinates. Building a model (its BVH and hull) takes tens of milliseconds
for 10,000 triangles and releases the GIL: threads flying one shape share one Model.)")
      .def("inspect", &inspect,
           "What `tetrapage inspect --report` writes (the same keys), and the index's "
           "memory_budget_bytes, as a dict.")
      .def(
          "preload",
          [](const Index& i) {
            py::gil_scoped_release unlocked;
            i.index->preload();
          },
          "Loads every shard (raises InputError when they do not fit the budget).")
      .def("__repr__", [](const Index& i) {
        return "<tetrapage.Index '" + i.index->path().string() + "', " +
               std::to_string(i.index->header().input_triangles) + " triangles>";
      });
}

}  // namespace tetrapage::python
