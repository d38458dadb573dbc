#pragma once
// Shared by the fuzz targets that read in chunks: what the chunks held, appended, and the check
// that it is the whole read's soup (a trap, libFuzzer's crash, where it is not).

#include <array>
#include <cstdint>
#include <vector>

#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/formats/mesh/MeshReader.h"

namespace tetrapage::fuzz {

struct ChunkedRead {
  std::vector<std::array<Vec3, 3>> corners;
  std::vector<std::uint32_t> parts;
  TriangleSoup names;  ///< the parts returned at the end

  /// Collects every chunk handed to `chunks` (each chunk's indices checked in range).
  void collect_from(SoupChunks& chunks) {
    chunks.take = [this](TriangleSoup&& chunk) {
      for (std::size_t t = 0; t < chunk.triangle_count(); ++t) {
        for (const std::uint32_t corner : chunk.triangles[t])
          if (corner >= chunk.vertices.size()) __builtin_trap();
        corners.push_back(chunk.corners(t));
        parts.push_back(chunk.part_of[t]);
      }
    };
  }
};

/// What every caller relies on of a soup: indices in range, one part per triangle.
inline void check_soup(const TriangleSoup& soup) {
  for (const auto& triangle : soup.triangles)
    for (const std::uint32_t corner : triangle)
      if (corner >= soup.vertices.size()) __builtin_trap();
  if (soup.part_of.size() != soup.triangles.size()) __builtin_trap();
}

/// The chunks, appended, are `whole`'s triangles, parts and part names.
inline void check_same_soup(const ChunkedRead& chunked, const TriangleSoup& whole) {
  if (chunked.corners.size() != whole.triangle_count()) __builtin_trap();
  for (std::size_t t = 0; t < whole.triangle_count(); ++t)
    if (chunked.corners[t] != whole.corners(t) || chunked.parts[t] != whole.part_of[t])
      __builtin_trap();
  if (chunked.names.part_names != whole.part_names || chunked.names.part_paths != whole.part_paths)
    __builtin_trap();
}

}  // namespace tetrapage::fuzz
