// One mesh reader (the format is chosen by TETRAPAGE_FUZZ_EXTENSION: .ply, .obj, .stl, .off)
// on arbitrary bytes: it must return a soup or throw a tetrapage::Error, nothing else; read in
// chunks (of 3 triangles, the vertex table past 5 vertices on disk) it must succeed or fail as
// the whole read does, and its chunks appended must be the whole read's triangles and parts.

#include <optional>

#include "FuzzSupport.h"
#include "tetrapage/formats/Error.h"
#include "tetrapage/formats/MeshReader.h"

namespace {

struct Chunked {
  std::vector<std::array<tetrapage::Vec3, 3>> corners;
  std::vector<std::uint32_t> parts;
  tetrapage::TriangleSoup names;
};

std::optional<Chunked> read_in_chunks(const std::filesystem::path& path) {
  Chunked read;
  tetrapage::SoupChunks chunks;
  chunks.triangles = 3;
  chunks.held_vertices = 5;
  chunks.vertex_cache_bytes = 1;
  chunks.take = [&](tetrapage::TriangleSoup&& chunk) {
    for (std::size_t t = 0; t < chunk.triangle_count(); ++t) {
      read.corners.push_back(chunk.corners(t));
      read.parts.push_back(chunk.part_of[t]);
    }
  };
  try {
    read.names = tetrapage::read_mesh_in_chunks(path, nullptr, chunks);
  } catch (const tetrapage::Error&) {
    return std::nullopt;
  }
  return read;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static tetrapage::fuzz::TempFile file(TETRAPAGE_FUZZ_EXTENSION);
  file.write(data, size);
  std::optional<tetrapage::TriangleSoup> whole;
  try {
    whole = tetrapage::read_mesh(file.path());
    // What every caller relies on: indices in range, one part per triangle.
    for (const auto& triangle : whole->triangles)
      for (const std::uint32_t corner : triangle)
        if (corner >= whole->vertices.size()) __builtin_trap();
    if (whole->part_of.size() != whole->triangles.size()) __builtin_trap();
  } catch (const tetrapage::Error&) {
  }
  const std::optional<Chunked> chunked = read_in_chunks(file.path());
  if (whole.has_value() != chunked.has_value()) __builtin_trap();
  if (!whole) return 0;
  if (chunked->corners.size() != whole->triangle_count()) __builtin_trap();
  for (std::size_t t = 0; t < whole->triangle_count(); ++t)
    if (chunked->corners[t] != whole->corners(t) || chunked->parts[t] != whole->part_of[t])
      __builtin_trap();
  if (chunked->names.part_names != whole->part_names || chunked->names.part_paths != whole->part_paths)
    __builtin_trap();
  return 0;
}
