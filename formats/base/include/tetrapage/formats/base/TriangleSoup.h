#pragma once
/// @file TriangleSoup.h
/// The in-memory triangle set every reader returns and every stage consumes: double
/// coordinates, indexed triangles, and a part id per triangle.

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace tetrapage {

using Vec3 = std::array<double, 3>;
using TriangleIndices = std::array<std::uint32_t, 3>;

/// Axis-aligned bounding box; empty while lo > hi.
struct BoundingBox {
  Vec3 lo{1e300, 1e300, 1e300};
  Vec3 hi{-1e300, -1e300, -1e300};

  bool empty() const { return lo[0] > hi[0]; }
  void extend(const Vec3& p) {
    // Selects rather than branches (minsd and maxsd; the same results, NaN included): boxes of
    // triangles in no particular order mispredicted a branch in two.
    for (int a = 0; a < 3; ++a) {
      lo[a] = p[a] < lo[a] ? p[a] : lo[a];
      hi[a] = p[a] > hi[a] ? p[a] : hi[a];
    }
  }
  void extend(const BoundingBox& b) {
    if (b.empty()) return;
    if (empty()) {
      *this = b;  // extending the empty box's +-1e300 would clamp a box beyond them
      return;
    }
    extend(b.lo);
    extend(b.hi);
  }
  Vec3 size() const { return {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]}; }
  Vec3 center() const {
    return {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
  }
};

/// Indexed triangles with a part id per triangle. Parts are the assembly's instances:
/// part_names[part_of[t]] names the part triangle t belongs to, and part_path(p) says where that
/// instance sits in the assembly.
struct TriangleSoup {
  std::vector<Vec3> vertices;
  std::vector<TriangleIndices> triangles;
  std::vector<std::uint32_t> part_of;  ///< one per triangle
  /// What the file calls each part (a STEP product, an OBJ group, a manifest part); several
  /// instances of one part share it.
  std::vector<std::string> part_names;
  /// Each part's instance path, unique in the model: the instances' names from the root down,
  /// joined by '/' ("rack/board#3/U7"). Empty when every path is the part's name (one file).
  std::vector<std::string> part_paths;

  std::size_t triangle_count() const { return triangles.size(); }
  std::size_t part_count() const { return part_names.size(); }
  const std::string& part_path(std::size_t part) const {
    return part_paths.empty() ? part_names[part] : part_paths[part];
  }
  /// Adds a part (no triangles yet) and returns its id; an empty path is the name.
  std::uint32_t add_part(std::string name, std::string path = {});

  /// The three corners of triangle t.
  std::array<Vec3, 3> corners(std::size_t t) const {
    const auto& tri = triangles[t];
    return {vertices[tri[0]], vertices[tri[1]], vertices[tri[2]]};
  }
  /// Every triangle's corners, in order (what the in-core methods and oracles are built over).
  std::vector<std::array<Vec3, 3>> all_corners() const {
    std::vector<std::array<Vec3, 3>> out;
    out.reserve(triangles.size());
    for (std::size_t t = 0; t < triangles.size(); ++t) out.push_back(corners(t));
    return out;
  }

  BoundingBox bounds() const {
    BoundingBox box;
    if (vertices.empty()) return box;
    // From the first vertex: the empty box's +-1e300 would clamp coordinates beyond them.
    box.lo = box.hi = vertices.front();
    for (const auto& v : vertices) box.extend(v);
    return box;
  }

  /// Appends another soup's triangles as new parts (vertex indices are shifted).
  void append(const TriangleSoup& other);
};

/// What a reader saw besides the triangles it kept.
struct ReadReport {
  std::string path;
  std::string format;                       ///< "obj", "stl", "ply", "off", "assimp:gltf", ...
  std::uint64_t triangles_read = 0;         ///< after fan-triangulating, degenerate ones included
  std::uint64_t degenerate_dropped = 0;     ///< zero area (exactly) or repeated indices
  /// The dropped triangles' 0-based positions among the triangles_read (the file's faces in
  /// order, each fan-triangulated), ascending; triangle_position() (MeshReader.h) maps a kept
  /// triangle's id back to its position.
  std::vector<std::uint64_t> dropped_positions;
  std::uint64_t polygons_triangulated = 0;  ///< faces with more than three corners
  std::uint64_t bytes = 0;                  ///< file size
  double seconds = 0.0;
  /// "ascii", "binary", "binary_little_endian", "binary_big_endian"; empty through Assimp.
  std::string encoding;
  /// The unit of the coordinates the reader returned ("mm", a name metres_per_unit knows);
  /// empty when the file does not say.
  std::string length_unit;
  /// CAD input: the largest chordal deviation the tessellation was asked for, in the
  /// coordinates returned (0: the file held triangles, used as they are).
  double tessellation_deflection = 0.0;
  /// CAD input: the shapes left out because they failed to tessellate (skip_bad_parts), each
  /// "instance path: reason".
  std::vector<std::string> skipped_parts;
};

}  // namespace tetrapage
