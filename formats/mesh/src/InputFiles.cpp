// files_read_from (FileChecks.h): every file a read of an input opens, so that an output is
// checked against all of them, however they are named.

#include <cctype>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <set>
#include <string>

#include <nlohmann/json.hpp>

#include "GltfDocument.h"
#include "PathSupport.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/FileChecks.h"
#include "tetrapage/formats/mesh/Manifest.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;

// A .gltf larger than this is not parsed here (its size is its data URIs: no file names).
constexpr std::uintmax_t kLargestGltfJson = std::uintmax_t(64) << 20;

// The JSON of a glTF, or nothing when it cannot be had (its reader then says why).
std::string gltf_json(const fs::path& path) {
  std::error_code error;
  if (detail::lower_extension(path) == ".gltf" && fs::file_size(path, error) > kLargestGltfJson) return {};
  try {
    return detail::read_gltf_json(path);
  } catch (const Error&) {
    return {};
  }
}

// Every "uri" string member anywhere in a glTF document: buffers and images (glTF 2 lists them
// in arrays, glTF 1 in objects keyed by id), shaders (glTF 1) and extensions alike. Walked with
// a stack of its own: a document may nest deeply.
void add_uris(const nlohmann::json& document, std::vector<std::string>& uris) {
  std::vector<const nlohmann::json*> pending{&document};
  while (!pending.empty()) {
    const nlohmann::json& value = *pending.back();
    pending.pop_back();
    if (value.is_object()) {
      for (const auto& [key, member] : value.items()) {
        if (key == "uri" && member.is_string()) uris.push_back(member.get<std::string>());
        pending.push_back(&member);
      }
    } else if (value.is_array()) {
      for (const auto& member : value) pending.push_back(&member);
    }
  }
}

// The files a glTF's URIs name (data URIs and other schemes are not files).
void add_gltf_files(const fs::path& path, std::vector<fs::path>& files) {
  // No parser callback: nlohmann's callback parser rescans a container after each of its values.
  const nlohmann::json document = nlohmann::json::parse(gltf_json(path), nullptr, false);
  if (!document.is_object()) return;
  std::vector<std::string> uris;
  add_uris(document, uris);
  for (const std::string& uri : uris) {
    if (uri.empty() || uri.rfind("data:", 0) == 0 || uri.find("://") != std::string::npos) continue;
    // Readers differ on percent escapes (Assimp 5.2 opens the URI as written): both count.
    files.push_back(path.parent_path() / uri);
    if (const std::string decoded = detail::decoded_uri(uri); decoded != uri) files.push_back(path.parent_path() / decoded);
  }
}

void add_mesh_files(const fs::path& path, std::vector<fs::path>& files) {
  files.push_back(path);
  const std::string extension = detail::lower_extension(path);
  if (extension == ".gltf" || extension == ".glb") add_gltf_files(path, files);
}

void add_manifest_files(const Manifest& manifest, std::set<const Manifest*>& seen,
                        std::vector<fs::path>& files) {
  if (!seen.insert(&manifest).second) return;
  files.push_back(manifest.path);
  for (const ManifestPart& part : manifest.parts) {
    if (part.assembly) {
      add_manifest_files(*part.assembly, seen, files);
    } else {
      add_mesh_files(part.file, files);
    }
  }
}

}  // namespace

std::vector<fs::path> files_read_from(const fs::path& input) {
  std::vector<fs::path> files;
  if (input.empty()) return files;
  std::error_code error;
  if (is_manifest_path(input) && fs::is_regular_file(input, error)) {
    const Manifest manifest = read_manifest(input);
    std::set<const Manifest*> seen;
    add_manifest_files(manifest, seen, files);
  } else {
    add_mesh_files(input, files);
  }
  return files;
}

}  // namespace tetrapage
