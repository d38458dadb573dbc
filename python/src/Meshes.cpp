// Meshes and pose files: tetrapage.Mesh, read_mesh, write_mesh, read_poses, write_poses.

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "Bindings.h"
#include "tetrapage/formats/CadReader.h"
#include "tetrapage/formats/MeshReader.h"
#include "tetrapage/formats/MeshWriter.h"

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
    if (!part_names.empty()) mesh.soup.part_names = {part_names.front()};
    return mesh;
  }
  const auto parts =
      py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(part_of);
  if (!parts || parts.ndim() != 1 || std::size_t(parts.shape(0)) != mesh.soup.triangles.size())
    throw InputError("part_of: one integer per triangle is expected (" +
                     std::to_string(mesh.soup.triangles.size()) + ")");
  std::int64_t largest = -1;
  for (py::ssize_t t = 0; t < parts.shape(0); ++t) {
    if (parts.at(t) < 0) throw InputError("part_of[" + std::to_string(t) + "] is negative");
    largest = std::max(largest, parts.at(t));
  }
  if (part_names.empty())
    for (std::int64_t p = 0; p <= largest; ++p) part_names.push_back("part " + std::to_string(p));
  if (std::int64_t(part_names.size()) <= largest)
    throw InputError("part_names: " + std::to_string(part_names.size()) +
                     " names for part ids up to " + std::to_string(largest));
  mesh.soup.part_names = std::move(part_names);
  mesh.soup.part_of.assign(parts.data(), parts.data() + parts.shape(0));
  return mesh;
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
      .def_property_readonly("part_names", [](const Mesh& m) { return m.soup.part_names; })
      .def_property_readonly("part_paths",
                             [](const Mesh& m) {
                               std::vector<std::string> paths;
                               for (std::size_t p = 0; p < m.soup.part_count(); ++p)
                                 paths.push_back(m.soup.part_path(p));
                               return paths;
                             })
      .def_readonly("length_unit", &Mesh::length_unit,
                    "The unit the file states (\"mm\" for STEP and IGES), or \"\".")
      .def_property_readonly(
          "bounds",
          [](const Mesh& m) {
            const BoundingBox box = m.soup.bounds();
            return box_array(box.lo, box.hi);
          },
          "(2, 3): the lowest and highest corner of the vertices' box.")
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
        ReadReport report;
        Mesh mesh;
        {
          py::gil_scoped_release unlocked;
          mesh.soup = read_mesh(path, &report, tessellation);
        }
        mesh.length_unit = report.length_unit;
        return mesh;
      },
      py::arg("path"), py::arg("deflection") = "0.1%", py::arg("angular_deflection") = 0.5,
      py::arg("skip_bad_parts") = false,
      "Reads OBJ, PLY, OFF, STL, glTF/GLB, STEP or IGES into a Mesh. STEP and IGES are read in "
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
