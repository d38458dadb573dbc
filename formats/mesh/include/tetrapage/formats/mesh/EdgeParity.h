#pragma once
/// @file EdgeParity.h
/// Whether a triangle surface is closed in the sense ray parity needs: every edge (an unordered
/// pair of vertex positions) is used by an even number of triangles, so that the number of
/// crossings between a segment and the surface has the same parity along every path between
/// the same two points. Streaming and in constant memory: each edge's 128-bit hash is folded in
/// by XOR, so pairs cancel; an open surface reads as closed only if its unpaired edges' hashes
/// cancel, with probability about 2^-128.
#include <array>
#include <cstdint>

#include "tetrapage/formats/base/TriangleSoup.h"

namespace tetrapage {

class EdgeParity {
 public:
  /// Folds in the three edges of the triangle a, b, c (vertex positions, compared bit for bit
  /// after -0.0 is read as 0.0).
  void add_triangle(const Vec3& a, const Vec3& b, const Vec3& c);
  void add_triangle(const std::array<Vec3, 3>& t) { add_triangle(t[0], t[1], t[2]); }

  /// A vertex position's 128-bit hash: a soup whose vertices are shared by several triangles
  /// hashes each once and folds its triangles in with add_hashed_triangle.
  using VertexHash = std::array<std::uint64_t, 2>;
  static VertexHash hash_vertex(const Vec3& p);
  /// The same as add_triangle for the positions whose hashes these are.
  void add_hashed_triangle(const VertexHash& a, const VertexHash& b, const VertexHash& c);
  /// Combines another accumulator's triangles (for parallel folds).
  void merge(const EdgeParity& other) {
    state_[0] ^= other.state_[0];
    state_[1] ^= other.state_[1];
  }
  /// Every edge folded so far is used an even number of times (true when nothing was added).
  bool closed() const { return state_[0] == 0 && state_[1] == 0; }

 private:
  std::array<std::uint64_t, 2> state_{};
};

}  // namespace tetrapage
