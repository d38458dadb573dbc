// Meshes and pose files: tetrapage.Mesh, read_mesh, write_mesh, read_poses, write_poses.

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cmath>
#include <limits>

#include "Bindings.h"
#include "tetrapage/formats/mesh/CadReader.h"
#include "tetrapage/formats/mesh/Manifest.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/MeshWriter.h"

namespace tetrapage::python {

namespace {

py::array_t<std::uint32_t> triangles_array(const TriangleSoup& soup) {
  py::array_t<std::uint32_t> array({py::ssize_t(soup.triangles.size()), py::ssize_t(3)});
  if (!soup.triangles.empty())
    std::copy_n(soup.triangles.front().data(), 3 * soup.triangles.size(), array.mutable_data());
  return array;
}

py::array_t<double> poses_array(const std::vector<Pose>& poses) {
  py::array_t<double> array({py::ssize_t(poses.size()), py::ssize_t(7)});
  double* out = array.mutable_data();
  for (const Pose& pose : poses) {
    out = std::copy(pose.translation.begin(), pose.translation.end(), out);
    out = std::copy(pose.rotation.begin(), pose.rotation.end(), out);
  }
  return array;
}

Mesh mesh_of_arrays(py::handle vertices, py::handle triangles, py::handle part_of,
                    std::vector<std::string> part_names) {
  Mesh mesh{soup_from_arrays(vertices, triangles), {}};
  if (part_of.is_none()) {
    if (part_names.size() > 1)
      throw InputError("part_names: " + std::to_string(part_names.size()) +
                       " names, but without part_of every triangle is in one part");
    if (!part_names.empty()) mesh.soup.part_names = {part_names.front()};
    return mesh;
  }
  const py::array parts_any = as_array(part_of, "part_of");
  const char kind = parts_any.dtype().kind();
  // An empty list reads as float64: no id in it to be fractional.
  if (kind != 'i' && kind != 'u' && parts_any.size() != 0)
    throw InputError("part_of: dtype " + py::str(parts_any.dtype()).cast<std::string>() +
                     " is not an integer type (part ids)");
  // Ids are compared as uint64: a uint64 id beyond int64's range must not wrap to a negative one.
  const auto parts =
      py::array_t<std::uint64_t, py::array::c_style | py::array::forcecast>::ensure(parts_any);
  if (parts.ndim() != 1 || std::size_t(parts.shape(0)) != mesh.soup.triangles.size())
    throw InputError("part_of: one integer per triangle is expected (" +
                     std::to_string(mesh.soup.triangles.size()) + ")");
  // Part ids are uint32 in the soup (a larger one would be truncated to another part's id).
  std::uint64_t parts_needed = 0;  // the largest id + 1
  for (py::ssize_t t = 0; t < parts.shape(0); ++t) {
    const std::uint64_t id = parts.at(t);
    if (kind == 'i' && std::int64_t(id) < 0)
      throw InputError("part_of[" + std::to_string(t) + "] is negative");
    if (id > std::numeric_limits<std::uint32_t>::max())
      throw InputError("part_of[" + std::to_string(t) + "] = " + std::to_string(id) +
                       " is beyond the largest part id " +
                       std::to_string(std::numeric_limits<std::uint32_t>::max()));
    parts_needed = std::max(parts_needed, id + 1);
  }
  if (part_names.empty()) {
    // One made-up name per id up to the largest: without this bound an id of 2**31 would make
    // two billion names (a hang, then an allocation failure).
    if (parts_needed > mesh.soup.triangles.size())
      throw InputError("part_of: part id " + std::to_string(parts_needed - 1) +
                       " is not below the triangle count " +
                       std::to_string(mesh.soup.triangles.size()) +
                       " (give part_names to number parts beyond it)");
    for (std::uint64_t p = 0; p < parts_needed; ++p)
      part_names.push_back("part " + std::to_string(p));
  }
  if (part_names.size() < parts_needed)
    throw InputError("part_names: " + std::to_string(part_names.size()) +
                     " names for part ids up to " + std::to_string(parts_needed - 1));
  mesh.soup.part_names = std::move(part_names);
  mesh.soup.part_of.assign(parts.data(), parts.data() + parts.shape(0));
  return mesh;
}

Mesh scaled(const Mesh& mesh, double factor) {
  if (!(factor > 0) || !std::isfinite(factor))
    throw InputError("scaled: the factor " + std::to_string(factor) + " is not a positive number");
  Mesh copy = mesh;
  for (Vec3& vertex : copy.soup.vertices)
    for (double& c : vertex) c *= factor;
  copy.length_unit.clear();
  return copy;
}

Mesh in_unit(const Mesh& mesh, const std::string& unit, py::handle from_unit) {
  std::string from = mesh.length_unit;
  if (!from_unit.is_none()) {
    const std::string given = from_unit.cast<std::string>();
    metres_per_unit(given);  // an unknown unit is an InputError naming it
    if (!from.empty() && from != given)
      throw InputError("in_unit: from_unit " + given + ", but the mesh states " + from);
    from = given;
  }
  if (from.empty()) throw InputError("in_unit: the mesh states no unit: give from_unit");
  Mesh copy = scaled(mesh, metres_per_unit(from) / metres_per_unit(unit));
  copy.length_unit = unit;
  return copy;
}

}  // namespace

void bind_meshes(py::module_& module) {
  py::class_<Mesh>(module, "Mesh",
                   "Triangles with a part per triangle, as read from a file or made from arrays.")
      .def(py::init(&mesh_of_arrays), py::arg("vertices"), py::arg("triangles"),
           py::arg("part_of") = py::none(), py::arg("part_names") = std::vector<std::string>{},
           "A mesh from (N, 3) vertices and (M, 3) integer triangles; part_of gives each "
           "triangle's part (default: all in one part), part_names their names.")
      .def_property_readonly(
          "vertices",
          [](const Mesh& m) {
            return double_array(m.soup.vertices.empty() ? nullptr : m.soup.vertices.front().data(),
                                {py::ssize_t(m.soup.vertices.size()), 3});
          },
          "(N, 3) float64 vertex coordinates (a copy).")
      .def_property_readonly(
          "triangles", [](const Mesh& m) { return triangles_array(m.soup); },
          "(M, 3) uint32 vertex indices (a copy).")
      .def_property_readonly(
          "part_of",
          [](const Mesh& m) {
            return py::array_t<std::uint32_t>(py::ssize_t(m.soup.part_of.size()),
                                              m.soup.part_of.data());
          },
          "(M,) uint32: each triangle's part.")
      .def_property_readonly(
          "part_names", [](const Mesh& m) { return m.soup.part_names; },
          "Each part's name, by part (the values of part_of): what the file calls it (a STEP "
          "product, an OBJ group, a manifest part); instances of one part share it.")
      .def_property_readonly(
          "part_paths",
          [](const Mesh& m) {
            std::vector<std::string> paths;
            for (std::size_t p = 0; p < m.soup.part_count(); ++p)
              paths.push_back(m.soup.part_path(p));
            return paths;
          },
          "Each part's instance path, by part: the instances' names from the root down joined "
          "by '/' (\"rack/board#3/U7\"), unique in the model; the part's name for one file.")
      .def_readonly("length_unit", &Mesh::length_unit,
                    "The unit the file states (\"mm\" for STEP and IGES), or \"\".")
      .def_property_readonly(
          "bounds",
          [](const Mesh& m) {
            const BoundingBox box = m.soup.bounds();
            if (!box.empty()) return box_array(box.lo, box.hi);
            const double nan = std::numeric_limits<double>::quiet_NaN();
            return box_array({nan, nan, nan}, {nan, nan, nan});
          },
          "(2, 3): the lowest and highest corner of the vertices' box (NaN without vertices).")
      .def("scaled", &scaled, py::arg("factor"),
           "A copy with every coordinate times `factor` (positive); its unit is then unstated.")
      .def("in_unit", &in_unit, py::arg("unit"), py::arg("from_unit") = py::none(),
           "A copy in `unit` (\"mm\", \"m\", \"in\", ...), converted from the mesh's own "
           "length_unit, or from `from_unit` for a mesh that states none. For an object in an "
           "index's unit: mesh.in_unit(index.length_unit).")
      .def("__len__", [](const Mesh& m) { return m.soup.triangles.size(); })
      .def("__repr__", [](const Mesh& m) {
        return "<tetrapage.Mesh " + std::to_string(m.soup.triangles.size()) + " triangles, " +
               std::to_string(m.soup.vertices.size()) + " vertices, " +
               std::to_string(m.soup.part_count()) + " parts>";
      });

  module.def(
      "read_mesh",
      [](const std::filesystem::path& path, const std::string& deflection,
         double angular_deflection, bool skip_bad_parts) {
        TessellationOptions tessellation;
        set_deflection(tessellation, deflection, "deflection");
        tessellation.angular_deflection = angular_deflection;
        tessellation.skip_bad_parts = skip_bad_parts;
        Mesh mesh;
        py::gil_scoped_release unlocked;
        if (is_manifest_path(path)) {
          // An assembly, placed as every command places it, in its manifest's units.
          mesh.soup = load_inputs({path}, nullptr, Progress::silent(), tessellation);
          mesh.length_unit = read_manifest(path).units;
        } else {
          ReadReport report;
          mesh.soup = read_mesh(path, &report, tessellation);
          mesh.length_unit = report.length_unit;
        }
        return mesh;
      },
      py::arg("path"), py::arg("deflection") = "0.1%", py::arg("angular_deflection") = 0.5,
      py::arg("skip_bad_parts") = false,
      "Reads OBJ, PLY, OFF, STL, glTF/GLB, STEP, IGES or an assembly manifest (.json, placed in "
      "its units) into a Mesh. STEP and IGES are read in "
      "mm and tessellated: `deflection` is the largest distance between a triangle and the "
      "surface, as a percentage of each shape's diagonal (\"0.1%\") or a length in mm "
      "(\"0.01\"); `angular_deflection` in radians. Raises IoError, FormatError or InputError "
      "naming the file and what is wrong.");
  module.def(
      "write_mesh",
      [](const std::filesystem::path& path, py::handle mesh) {
        const TriangleSoup soup = soup_from_mesh_like(mesh, "mesh");
        py::gil_scoped_release unlocked;
        write_mesh(path, soup);
      },
      py::arg("path"), py::arg("mesh"),
      "Writes a Mesh (or a (vertices, triangles) pair) in the format the extension names "
      "(.obj, .ply, .off, .stl); PLY and OBJ keep the parts.");
  module.def(
      "read_poses",
      [](const std::filesystem::path& path) {
        std::vector<Pose> poses;
        {
          py::gil_scoped_release unlocked;
          poses = read_poses(path);
        }
        return poses_array(poses);
      },
      py::arg("path"), "Reads a pose file (CSV tx,ty,tz,qw,qx,qy,qz) as a (K, 7) float64 array.");
  module.def(
      "write_poses",
      [](const std::filesystem::path& path, py::handle poses) {
        const PoseBatch batch = poses_from_array(poses, "poses");
        py::gil_scoped_release unlocked;
        write_poses(path, batch.poses);
      },
      py::arg("path"), py::arg("poses"),
      "Writes poses ((K, 7) or (K, 4, 4)) as a pose file, every double exactly.");
}

}  // namespace tetrapage::python
