// One mesh reader (the format is chosen by TETRAPAGE_FUZZ_EXTENSION: .ply, .obj, .stl, .off,
// .gltf, .glb) on arbitrary bytes. A glTF our reader leaves to Assimp is skipped: Assimp runs in
// a child process per input, which a hang would hold up to 600 s, and its crash ends the child
// only. The reader must return a soup or throw a tetrapage::Error, nothing else; read in
// chunks (of 3 triangles, the vertex table past 5 vertices on disk) it must succeed or fail as
// the whole read does, and its chunks appended must be the whole read's triangles and parts.

#include <optional>

#include "ChunkedRead.h"
#include "FuzzSupport.h"
#include "GltfDocument.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/MeshReader.h"

namespace {

std::optional<tetrapage::fuzz::ChunkedRead> read_in_chunks(const std::filesystem::path& path) {
  tetrapage::fuzz::ChunkedRead read;
  tetrapage::SoupChunks chunks;
  chunks.triangles = 3;
  chunks.held_vertices = 5;
  chunks.vertex_cache_bytes = 1;
  read.collect_from(chunks);
  try {
    read.names = tetrapage::read_mesh_in_chunks(path, nullptr, chunks);
  } catch (const tetrapage::Error&) {
    return std::nullopt;
  }
  return read;
}

bool goes_to_assimp(const std::filesystem::path& path) {
  const std::string extension = path.extension().string();
  if (extension != ".gltf" && extension != ".glb") return false;
  try {
    return !tetrapage::detail::read_gltf_document(path, false).needs_assimp.empty();
  } catch (const tetrapage::Error&) {
    return false;  // the reads below refuse it
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static tetrapage::fuzz::TempFile file(TETRAPAGE_FUZZ_EXTENSION);
  file.write(data, size);
  if (goes_to_assimp(file.path())) return 0;
  std::optional<tetrapage::TriangleSoup> whole;
  try {
    whole = tetrapage::read_mesh(file.path());
    tetrapage::fuzz::check_soup(*whole);
  } catch (const tetrapage::Error&) {
  }
  const std::optional<tetrapage::fuzz::ChunkedRead> chunked = read_in_chunks(file.path());
  if (whole.has_value() != chunked.has_value()) __builtin_trap();
  if (whole) tetrapage::fuzz::check_same_soup(*chunked, *whole);
  return 0;
}
