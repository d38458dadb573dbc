#pragma once
// Small solids and sheets built into a soup, for tests that need closed and open components
// on exactly representable coordinates.

#include <array>
#include <cstdint>

#include "tetrapage/formats/base/TriangleSoup.h"

namespace tetrapage::test_solids {

/// An axis-aligned box (12 triangles, outward), or without its top (10: an open shell).
inline void add_box(TriangleSoup& soup, const Vec3& lo, const Vec3& hi, bool open_top = false) {
  const auto base = std::uint32_t(soup.vertices.size());
  for (int i = 0; i < 8; ++i)
    soup.vertices.push_back({(i & 1) ? hi[0] : lo[0], (i & 2) ? hi[1] : lo[1], (i & 4) ? hi[2] : lo[2]});
  const std::array<std::array<std::uint32_t, 4>, 6> faces{
      {{0, 2, 3, 1}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}, {4, 5, 7, 6}}};
  for (std::size_t f = 0; f < (open_top ? 5u : 6u); ++f) {
    soup.triangles.push_back({base + faces[f][0], base + faces[f][1], base + faces[f][2]});
    soup.triangles.push_back({base + faces[f][0], base + faces[f][2], base + faces[f][3]});
  }
}

/// A tetrahedron, closed (4 triangles).
inline void add_tetra(TriangleSoup& soup, const std::array<Vec3, 4>& corners) {
  const auto base = std::uint32_t(soup.vertices.size());
  for (const Vec3& c : corners) soup.vertices.push_back(c);
  for (const auto& t : std::array<TriangleIndices, 4>{{{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}})
    soup.triangles.push_back({base + t[0], base + t[1], base + t[2]});
}

/// An open quadrilateral sheet a, b, c, d (2 triangles).
inline void add_quad(TriangleSoup& soup, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const auto base = std::uint32_t(soup.vertices.size());
  soup.vertices.insert(soup.vertices.end(), {a, b, c, d});
  soup.triangles.push_back({base, base + 1, base + 2});
  soup.triangles.push_back({base, base + 2, base + 3});
}

/// A copy of `soup` scaled by s and moved by o (rounded as doubles).
inline TriangleSoup placed(TriangleSoup soup, double s, const Vec3& o) {
  for (Vec3& v : soup.vertices)
    for (int a = 0; a < 3; ++a) v[a] = o[a] + s * v[a];
  return soup;
}

}  // namespace tetrapage::test_solids
