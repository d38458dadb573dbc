#pragma once
/// @file MeshLibrary.h
/// The real meshes that the scene and object generators copy: closed, well-known models
/// (CGAL's data meshes, unpacked into the build tree by the configure step), loaded once and
/// kept in memory (the curated set is about 200,000 triangles). Meshes are sorted by file
/// name, so a seed gives the same scene on every machine holding the same files.

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "tetrapage/formats/base/Progress.h"
#include "tetrapage/formats/base/TriangleSoup.h"

namespace tetrapage {

struct LibraryMesh {
  std::string name;            ///< the file's stem ("elephant")
  std::filesystem::path path;  ///< where it was read from (empty for meshes built in memory)
  TriangleSoup soup;           ///< one part, as read (degenerate triangles dropped)
  BoundingBox bounds;

  std::size_t triangle_count() const { return soup.triangle_count(); }
};

class MeshLibrary {
 public:
  /// A library of meshes built in memory (tests, callers with their own models).
  /// The meshes are sorted by name; each soup's triangles must index its own vertices.
  /// @throw InputError if `meshes` is empty, or a mesh has no triangle or an index out of
  ///        range (names the mesh and the triangle).
  explicit MeshLibrary(std::vector<LibraryMesh> meshes);

  /// The closed, manifold, well-known models used from the default folder, in name order
  /// (those present are used): anchor, armadillo, bull, bunny00, camel, couplingdown, cow,
  /// eight, elephant, fandisk, femur, hand, homer, knot1, pinion_small, rotor_small,
  /// triceratops, turbine. (CGAL's blade, lion-head, mannequin-devil and mech-holes-shark
  /// have open boundaries, so "inside an obstacle" would not be defined for them.)
  static std::span<const std::string> curated_names();

  /// $TETRAPAGE_MESH_DIR if set and not empty, otherwise the folder the build unpacked
  /// CGAL's meshes into (TETRAPAGE_DEFAULT_MESH_DIR).
  static std::filesystem::path default_folder();

  /// Loads the curated models present in default_folder(). A folder given through
  /// $TETRAPAGE_MESH_DIR that holds none of them is loaded whole, as load_folder() does.
  /// @throw InputError if no usable mesh is found (the message says to run `make deps` or to
  ///        pass --meshes DIR).
  static MeshLibrary load_default(Progress& progress = Progress::silent());

  /// Loads every .off, .ply, .obj and .stl file of `folder` (not recursive), sorted by file
  /// name. A file that cannot be read is skipped and listed in skipped().
  /// @throw InputError if `folder` is not a folder or holds no usable mesh (names the folder
  ///        and the files that were skipped, with their reasons).
  static MeshLibrary load_folder(const std::filesystem::path& folder,
                                 Progress& progress = Progress::silent());

  std::span<const LibraryMesh> meshes() const { return meshes_; }
  std::size_t size() const { return meshes_.size(); }
  const LibraryMesh& operator[](std::size_t i) const { return meshes_[i]; }

  /// Files that were found but not used, each as "file: reason".
  std::span<const std::string> skipped() const { return skipped_; }
  /// The folder the meshes were read from (empty for a library built in memory).
  const std::filesystem::path& folder() const { return folder_; }

  std::uint64_t total_triangles() const;
  std::size_t smallest_triangle_count() const;
  std::size_t largest_triangle_count() const;

 private:
  MeshLibrary() = default;
  // Reads each file (a file that fails is skipped and listed), as both loaders do.
  static MeshLibrary load_files(const std::filesystem::path& folder,
                                std::span<const std::filesystem::path> files, Progress& progress);

  std::vector<LibraryMesh> meshes_;
  std::vector<std::string> skipped_;
  std::filesystem::path folder_;
};

}  // namespace tetrapage
