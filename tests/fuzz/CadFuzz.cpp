// STEP or IGES reading (the extension is TETRAPAGE_FUZZ_EXTENSION) on arbitrary bytes through
// TessellatedFile: the pre-scan in this process, OpenCASCADE in its child, whose crash, hang or
// runaway allocation must come back as a tetrapage::Error; then its instances placed whole and
// in chunks of 3 triangles, which must succeed or fail alike and give the same triangles and
// parts. Slow (a process per input): not in `make fuzz`'s default targets.

#include <optional>
#include <vector>

#include "FuzzSupport.h"
#include "tetrapage/formats/Error.h"
#include "tetrapage/formats/TessellatedFile.h"

namespace {

struct Chunked {
  std::vector<std::array<tetrapage::Vec3, 3>> corners;
  std::vector<std::uint32_t> part_of;
  tetrapage::TriangleSoup names;
};

std::optional<Chunked> place_in_chunks(const tetrapage::TessellatedFile& file) {
  Chunked placed;
  tetrapage::SoupChunks chunks;
  chunks.triangles = 3;
  chunks.take = [&](tetrapage::TriangleSoup&& chunk) {
    for (std::size_t t = 0; t < chunk.triangle_count(); ++t) {
      for (const std::uint32_t corner : chunk.triangles[t])
        if (corner >= chunk.vertices.size()) __builtin_trap();
      placed.corners.push_back(chunk.corners(t));
      placed.part_of.push_back(chunk.part_of[t]);
    }
  };
  tetrapage::ReadReport report;
  try {
    placed.names = file.place_in_chunks(chunks, report);
  } catch (const tetrapage::Error&) {
    return std::nullopt;
  }
  return placed;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static tetrapage::fuzz::TempFile file(TETRAPAGE_FUZZ_EXTENSION);
  file.write(data, size);
  tetrapage::TessellationOptions options;
  options.time_limit = 10;
  options.memory_limit = std::uint64_t(1) << 30;
  options.max_triangles = 1'000'000;
  tetrapage::ReadReport report;
  std::optional<tetrapage::TessellatedFile> tessellated;
  try {
    tessellated.emplace(file.path(), options, report);
  } catch (const tetrapage::Error&) {
    return 0;
  }
  std::optional<tetrapage::TriangleSoup> soup;
  try {
    soup = tessellated->place(report);
  } catch (const tetrapage::Error&) {
  }
  const std::optional<Chunked> chunked = place_in_chunks(*tessellated);
  if (soup.has_value() != chunked.has_value()) __builtin_trap();
  if (!soup) return 0;
  for (const auto& triangle : soup->triangles)
    for (const std::uint32_t corner : triangle)
      if (corner >= soup->vertices.size()) __builtin_trap();
  if (soup->part_of.size() != soup->triangles.size()) __builtin_trap();
  if (chunked->corners.size() != soup->triangle_count()) __builtin_trap();
  for (std::size_t t = 0; t < chunked->corners.size(); ++t)
    if (chunked->corners[t] != soup->corners(t) || chunked->part_of[t] != soup->part_of[t])
      __builtin_trap();
  if (chunked->names.part_names != soup->part_names || chunked->names.part_paths != soup->part_paths)
    __builtin_trap();
  return 0;
}
