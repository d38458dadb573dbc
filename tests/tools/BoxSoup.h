#pragma once
// Axis-aligned boxes as triangle soups, for the tools tests' hand-made environments.

#include <cstdint>
#include <string>

#include "tetrapage/formats/base/TriangleSoup.h"

namespace tetrapage::test {

/// Appends the closed, outward-oriented box [lo, hi] as 12 triangles and one part.
inline void add_box(TriangleSoup& soup, const Vec3& lo, const Vec3& hi) {
  const auto base = static_cast<std::uint32_t>(soup.vertices.size());
  for (int i = 0; i < 8; ++i)
    soup.vertices.push_back({(i & 1) ? hi[0] : lo[0], (i & 2) ? hi[1] : lo[1], (i & 4) ? hi[2] : lo[2]});
  const std::uint32_t faces[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                      {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  const auto part = static_cast<std::uint32_t>(soup.part_names.size());
  soup.part_names.push_back("box" + std::to_string(part));
  for (const auto& f : faces) {
    soup.triangles.push_back({base + f[0], base + f[1], base + f[2]});
    soup.part_of.push_back(part);
  }
}

}  // namespace tetrapage::test
