#include "tetrapage/tools/MeshLibrary.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cstdlib>
#include <system_error>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/MeshReader.h"

#ifndef TETRAPAGE_DEFAULT_MESH_DIR
#define TETRAPAGE_DEFAULT_MESH_DIR ""
#endif

namespace tetrapage {
namespace {

// Closed (no boundary edge), manifold models only, so that inside/outside is defined for
// every obstacle of a generated scene. In name order, the order in which the library holds them.
const std::array<std::string, 18> curated_models{"anchor",
                                                 "armadillo",
                                                 "bull",
                                                 "bunny00",
                                                 "camel",
                                                 "couplingdown",
                                                 "cow",
                                                 "eight",
                                                 "elephant",
                                                 "fandisk",
                                                 "femur",
                                                 "hand",
                                                 "homer",
                                                 "knot1",
                                                 "pinion_small",
                                                 "rotor_small",
                                                 "triceratops",
                                                 "turbine"};

std::string lower_case(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

bool is_mesh_file(const std::filesystem::path& path) {
  const std::string extension = lower_case(path.extension().string());
  return extension == ".off" || extension == ".ply" || extension == ".obj" || extension == ".stl";
}

LibraryMesh read_library_mesh(const std::filesystem::path& path) {
  LibraryMesh mesh;
  mesh.name = path.stem().string();
  mesh.path = path;
  mesh.soup = read_mesh(path);
  mesh.bounds = mesh.soup.bounds();
  return mesh;
}

std::string no_mesh_message(const std::filesystem::path& folder,
                            const std::vector<std::string>& skipped) {
  std::string message = "no usable mesh (.off, .ply, .obj, .stl) in '" + folder.string() +
                        "': run `make deps` (Debian's libcgal-demo provides the meshes) and "
                        "reconfigure, or pass --meshes DIR";
  for (const auto& reason : skipped) message += "; skipped " + reason;
  return message;
}

}  // namespace

MeshLibrary::MeshLibrary(std::vector<LibraryMesh> meshes) : meshes_(std::move(meshes)) {
  if (meshes_.empty()) throw InputError("mesh library: no mesh given");
  for (auto& mesh : meshes_) {
    if (mesh.soup.triangles.empty())
      throw InputError("mesh library: mesh '" + mesh.name + "' has no triangle");
    for (std::size_t t = 0; t < mesh.soup.triangles.size(); ++t)
      for (auto v : mesh.soup.triangles[t])
        if (v >= mesh.soup.vertices.size())
          throw InputError("mesh library: mesh '" + mesh.name + "' triangle " + std::to_string(t) +
                           " uses vertex " + std::to_string(v) + " of " +
                           std::to_string(mesh.soup.vertices.size()));
    mesh.bounds = mesh.soup.bounds();
  }
  std::stable_sort(meshes_.begin(), meshes_.end(),
                   [](const LibraryMesh& a, const LibraryMesh& b) { return a.name < b.name; });
}

std::span<const std::string> MeshLibrary::curated_names() {
  return curated_models;
}

std::filesystem::path MeshLibrary::default_folder() {
  if (const char* folder = std::getenv("TETRAPAGE_MESH_DIR"); folder != nullptr && *folder != 0)
    return folder;
  return TETRAPAGE_DEFAULT_MESH_DIR;
}

MeshLibrary MeshLibrary::load_files(const std::filesystem::path& folder,
                                    std::span<const std::filesystem::path> files, Progress& progress) {
  MeshLibrary library;
  library.folder_ = folder;
  for (const auto& path : files) {
    try {
      library.meshes_.push_back(read_library_mesh(path));
    } catch (const Error& e) {
      library.skipped_.push_back(path.filename().string() + ": " + e.what());
    }
    progress.advance();
  }
  if (library.meshes_.empty()) throw InputError(no_mesh_message(folder, library.skipped_));
  return library;
}

MeshLibrary MeshLibrary::load_default(Progress& progress) {
  const std::filesystem::path folder = default_folder();
  const char* from_environment = std::getenv("TETRAPAGE_MESH_DIR");
  const bool environment = from_environment != nullptr && *from_environment != 0;
  std::error_code ec;
  if (folder.empty() || !std::filesystem::is_directory(folder, ec))
    throw InputError("mesh folder '" + folder.string() + "'" +
                     (environment ? " (from $TETRAPAGE_MESH_DIR)" : "") +
                     " does not exist: run `make deps` (Debian's libcgal-demo provides the "
                     "meshes) and reconfigure, or pass --meshes DIR");
  std::vector<std::filesystem::path> present;
  for (const auto& name : curated_models) {
    const auto path = folder / (name + ".off");
    if (std::filesystem::is_regular_file(path, ec)) present.push_back(path);
  }
  if (present.empty() && environment) return load_folder(folder, progress);

  return load_files(folder, present, progress);
}

MeshLibrary MeshLibrary::load_folder(const std::filesystem::path& folder, Progress& progress) {
  std::error_code ec;
  if (!std::filesystem::is_directory(folder, ec))
    throw InputError("mesh folder '" + folder.string() + "' is not a folder");
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(folder, ec)) {
    if (entry.is_regular_file(ec) && is_mesh_file(entry.path())) files.push_back(entry.path());
  }
  if (ec) throw InputError("cannot list mesh folder '" + folder.string() + "': " + ec.message());
  // Directory order is the file system's; sorting makes the library (and the scenes) portable.
  std::sort(files.begin(), files.end(), [](const auto& a, const auto& b) {
    return a.filename().string() < b.filename().string();
  });

  return load_files(folder, files, progress);
}

std::uint64_t MeshLibrary::total_triangles() const {
  std::uint64_t total = 0;
  for (const auto& mesh : meshes_) total += mesh.triangle_count();
  return total;
}

std::size_t MeshLibrary::smallest_triangle_count() const {
  std::size_t smallest = meshes_.front().triangle_count();
  for (const auto& mesh : meshes_) smallest = std::min(smallest, mesh.triangle_count());
  return smallest;
}

std::size_t MeshLibrary::largest_triangle_count() const {
  std::size_t largest = 0;
  for (const auto& mesh : meshes_) largest = std::max(largest, mesh.triangle_count());
  return largest;
}

}  // namespace tetrapage
