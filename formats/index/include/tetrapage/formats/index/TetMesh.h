#pragma once
/// @file TetMesh.h
/// The coarse tetrahedral mesh of regions: vertices, positively oriented tets, and the
/// neighbour across each face. Built by preprocess, stored in the index, walked by the runtime.

#include <array>
#include <cstdint>
#include <vector>

#include "tetrapage/formats/base/TriangleSoup.h"

namespace tetrapage {

struct TetMesh {
  static constexpr std::uint32_t no_neighbour = 0xffffffffu;

  std::vector<Vec3> vertices;
  /// Corner indices; orient3d(v0, v1, v2, v3) > 0 for every tet.
  std::vector<std::array<std::uint32_t, 4>> tets;
  /// neighbours[t][i] shares the face of t opposite corner i; no_neighbour on the hull.
  std::vector<std::array<std::uint32_t, 4>> neighbours;

  std::size_t tet_count() const { return tets.size(); }
  std::array<Vec3, 4> corners(std::size_t t) const {
    const auto& c = tets[t];
    return {vertices[c[0]], vertices[c[1]], vertices[c[2]], vertices[c[3]]};
  }
  BoundingBox bounds(std::size_t t) const {
    BoundingBox box;
    for (auto v : tets[t]) box.extend(vertices[v]);
    return box;
  }
};

}  // namespace tetrapage
