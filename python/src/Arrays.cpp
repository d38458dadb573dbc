// numpy arrays in and out: poses, meshes, boxes, budgets. Every check names the argument and the
// entry at fault, and raises InputError (a ValueError) rather than letting a bad array through.

#include <array>
#include <cmath>
#include <limits>
#include <sstream>

#include "Bindings.h"
#include "tetrapage/formats/base/ByteSize.h"
#include "tetrapage/formats/base/Error.h"

namespace tetrapage::python {

namespace {

std::string shape_text(const py::array& array) {
  std::ostringstream text;
  text << '(';
  for (py::ssize_t axis = 0; axis < array.ndim(); ++axis)
    text << (axis ? ", " : "") << array.shape(axis);
  text << (array.ndim() == 1 ? ",)" : ")");
  return text.str();
}

std::string dtype_text(const py::array& array) {
  return py::str(array.dtype()).cast<std::string>();
}

}  // namespace

// Any array-like as an array; a value numpy cannot read as numbers is an InputError. ensure()
// does not throw: it returns a null array (the numpy error cleared) for what numpy refuses, such
// as a ragged list, and a null array must never reach dtype() or ndim().
py::array as_array(py::handle value, std::string_view what) {
  py::array array = py::array::ensure(value);
  if (!array) throw InputError(std::string(what) + ": not an array of numbers");
  return array;
}

namespace {

// The array as C-ordered float64, refusing what is not real numbers (bool, complex, text, objects).
py::array_t<double, py::array::c_style> real_array(py::handle value, std::string_view what) {
  py::array array = as_array(value, what);
  const char kind = array.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u')
    throw InputError(std::string(what) + ": dtype " + dtype_text(array) +
                     " is not a real number type (float64 is expected)");
  return py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(array);
}

// A rotation matrix's unit quaternion (qw, qx, qy, qz) by the largest of the four pivots.
std::array<double, 4> quaternion_of(const double* r) {
  const double trace = r[0] + r[4] + r[8];
  std::array<double, 4> q{};
  if (trace > 0) {
    const double s = 2 * std::sqrt(1 + trace);
    q = {0.25 * s, (r[7] - r[5]) / s, (r[2] - r[6]) / s, (r[3] - r[1]) / s};
  } else if (r[0] > r[4] && r[0] > r[8]) {
    const double s = 2 * std::sqrt(1 + r[0] - r[4] - r[8]);
    q = {(r[7] - r[5]) / s, 0.25 * s, (r[1] + r[3]) / s, (r[2] + r[6]) / s};
  } else if (r[4] > r[8]) {
    const double s = 2 * std::sqrt(1 + r[4] - r[0] - r[8]);
    q = {(r[2] - r[6]) / s, (r[1] + r[3]) / s, 0.25 * s, (r[5] + r[7]) / s};
  } else {
    const double s = 2 * std::sqrt(1 + r[8] - r[0] - r[4]);
    q = {(r[3] - r[1]) / s, (r[2] + r[6]) / s, (r[5] + r[7]) / s, 0.25 * s};
  }
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (double& c : q) c /= norm;
  return q;
}

// The rotation block must be orthonormal with determinant +1 to the matrix's own rounding
// (1e-9 of each product): a scaling or a shear is not a pose.
void check_rigid(const double* m, const std::string& where) {
  if (m[12] != 0 || m[13] != 0 || m[14] != 0 || m[15] != 1)
    throw InputError(where + ": the last row is not 0 0 0 1 (not a rigid motion)");
  for (int i = 0; i < 16; ++i)
    if (!std::isfinite(m[i])) throw InputError(where + ": holds a non-finite value");
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      const double dot =
          m[4 * a] * m[4 * b] + m[4 * a + 1] * m[4 * b + 1] + m[4 * a + 2] * m[4 * b + 2];
      if (std::fabs(dot - (a == b ? 1.0 : 0.0)) > 1e-9)
        throw InputError(where + ": the rotation block is not orthonormal (row " +
                         std::to_string(a) + " . row " + std::to_string(b) + " = " +
                         std::to_string(dot) + ")");
    }
  const double det = m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) +
                     m[2] * (m[4] * m[9] - m[5] * m[8]);
  if (det < 0) throw InputError(where + ": the rotation block is a reflection (determinant -1)");
}

Pose pose_of_matrix(const double* m, const std::string& where) {
  check_rigid(m, where);
  const double rotation[9] = {m[0], m[1], m[2], m[4], m[5], m[6], m[8], m[9], m[10]};
  Pose pose;
  pose.translation = {m[3], m[7], m[11]};
  pose.rotation = quaternion_of(rotation);
  return pose;
}

std::string entry(std::string_view what, py::ssize_t row) {
  return std::string(what) + "[" + std::to_string(row) + "]";
}

}  // namespace

PoseBatch poses_from_array(py::handle value, std::string_view what) {
  const auto array = real_array(value, what);
  const double* data = array.data();
  PoseBatch batch;
  if (array.ndim() == 1 && array.shape(0) == 7) {
    batch.single = true;
    Pose pose;
    pose.translation = {data[0], data[1], data[2]};
    pose.rotation = {data[3], data[4], data[5], data[6]};
    batch.poses.push_back(pose);
  } else if (array.ndim() == 2 && array.shape(1) == 7) {
    batch.poses.resize(std::size_t(array.shape(0)));
    for (std::size_t k = 0; k < batch.poses.size(); ++k) {
      const double* row = data + 7 * k;
      batch.poses[k].translation = {row[0], row[1], row[2]};
      batch.poses[k].rotation = {row[3], row[4], row[5], row[6]};
    }
  } else if (array.ndim() == 2 && array.shape(0) == 4 && array.shape(1) == 4) {
    batch.single = true;
    batch.poses.push_back(pose_of_matrix(data, std::string(what)));
  } else if (array.ndim() == 3 && array.shape(1) == 4 && array.shape(2) == 4) {
    batch.poses.resize(std::size_t(array.shape(0)));
    for (std::size_t k = 0; k < batch.poses.size(); ++k)
      batch.poses[k] = pose_of_matrix(data + 16 * k, entry(what, py::ssize_t(k)));
  } else {
    throw InputError(std::string(what) + ": shape " + shape_text(array) +
                     " is not (7,), (K, 7) (tx, ty, tz, qw, qx, qy, qz), (4, 4) or (K, 4, 4)");
  }
  return batch;
}

Pose pose_from_array(py::handle value, std::string_view what) {
  PoseBatch batch = poses_from_array(value, what);
  if (!batch.single)
    throw InputError(std::string(what) + ": one pose is expected ((7,) or (4, 4)), got " +
                     std::to_string(batch.poses.size()));
  return batch.poses.front();
}

TriangleSoup soup_from_arrays(py::handle vertices_value, py::handle triangles_value) {
  const auto vertices = real_array(vertices_value, "vertices");
  if (vertices.ndim() != 2 || vertices.shape(1) != 3)
    throw InputError("vertices: shape " + shape_text(vertices) + " is not (N, 3)");
  py::array triangles_any = as_array(triangles_value, "triangles");
  const char kind = triangles_any.dtype().kind();
  if (kind != 'i' && kind != 'u')
    throw InputError("triangles: dtype " + dtype_text(triangles_any) +
                     " is not an integer type (vertex indices)");
  const auto triangles =
      py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(triangles_any);
  if (triangles.ndim() != 2 || triangles.shape(1) != 3)
    throw InputError("triangles: shape " + shape_text(triangles) + " is not (M, 3)");
  if (triangles_any.dtype().kind() == 'u' && triangles_any.itemsize() == 8) {
    // uint64 beyond int64's range wraps in the cast: check the originals.
    const auto unsigned_indices =
        py::array_t<std::uint64_t, py::array::c_style | py::array::forcecast>::ensure(
            triangles_any);
    for (py::ssize_t i = 0; i < unsigned_indices.size(); ++i)
      if (unsigned_indices.data()[i] >= std::uint64_t(vertices.shape(0)))
        throw InputError("triangles: index " + std::to_string(unsigned_indices.data()[i]) +
                         " is not below the vertex count " + std::to_string(vertices.shape(0)));
  }
  TriangleSoup soup;
  soup.vertices.resize(std::size_t(vertices.shape(0)));
  std::copy_n(vertices.data(), 3 * soup.vertices.size(), soup.vertices.front().data());
  const py::ssize_t vertex_count = vertices.shape(0);
  soup.triangles.resize(std::size_t(triangles.shape(0)));
  for (py::ssize_t t = 0; t < triangles.shape(0); ++t)
    for (int c = 0; c < 3; ++c) {
      const std::int64_t index = triangles.at(t, c);
      if (index < 0 || index >= vertex_count)
        throw InputError("triangles[" + std::to_string(t) + ", " + std::to_string(c) +
                         "] = " + std::to_string(index) + " is not a vertex (there are " +
                         std::to_string(vertex_count) + ")");
      soup.triangles[std::size_t(t)][std::size_t(c)] = std::uint32_t(index);
    }
  soup.add_part("object");
  soup.part_of.assign(soup.triangles.size(), 0);
  return soup;
}

TriangleSoup soup_from_mesh_like(py::handle value, std::string_view what) {
  if (py::isinstance<Mesh>(value)) return value.cast<const Mesh&>().soup;
  if (py::isinstance<py::tuple>(value) || py::isinstance<py::list>(value)) {
    const py::sequence pair = py::reinterpret_borrow<py::sequence>(value);
    if (pair.size() == 2) return soup_from_arrays(pair[0], pair[1]);
  }
  throw InputError(std::string(what) +
                   ": a tetrapage.Mesh or a (vertices, triangles) pair is expected");
}

py::array_t<double> double_array(const double* values, std::vector<py::ssize_t> shape) {
  py::array_t<double> array(shape);
  std::copy_n(values, array.size(), array.mutable_data());
  return array;
}

py::array_t<double> box_array(const Vec3& lo, const Vec3& hi) {
  const double values[6] = {lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]};
  return double_array(values, {2, 3});
}

std::uint64_t whole_number(py::handle value, const char* what, std::uint64_t lowest,
                           std::uint64_t highest) {
  if (py::isinstance<py::int_>(value) && !py::isinstance<py::bool_>(value) &&
      value.cast<py::int_>() >= py::int_(lowest) && value.cast<py::int_>() <= py::int_(highest))
    return value.cast<std::uint64_t>();
  throw InputError(std::string(what) + ": " + py::repr(value).cast<std::string>() +
                   " is not a whole number from " + std::to_string(lowest) + " to " +
                   std::to_string(highest));
}

std::uint64_t memory_bytes(py::handle value, std::uint64_t default_bytes) {
  if (value.is_none()) return default_bytes;
  if (py::isinstance<py::str>(value)) return parse_byte_size(value.cast<std::string>());
  if (py::isinstance<py::int_>(value) && !py::isinstance<py::bool_>(value)) {
    // Compared as Python ints: cast<long long>() of 2**63 would raise a RuntimeError that names
    // nothing.
    if (value.cast<py::int_>() <= py::int_(0))
      throw InputError("memory: " + py::repr(value).cast<std::string>() + " bytes is not a budget");
    if (value.cast<py::int_>() > py::int_(std::numeric_limits<std::uint64_t>::max()))
      throw InputError("memory: " + py::repr(value).cast<std::string>() +
                       " bytes is beyond 2**64 - 1");
    return value.cast<std::uint64_t>();
  }
  throw InputError(
      "memory: give a byte count or a size such as \"256M\" (k, M, G, T: powers of 1024)");
}

}  // namespace tetrapage::python
