#pragma once
// Internal: where two non-coplanar triangles cut the line their planes share, as intervals
// whose ends are named by edges (no point constructed), and the exact comparison of two
// ends along that line. Shared by the intersection test and the contact construction.
// Not installed.

#include "tetrapage/runtime/geometry/Predicates.h"

namespace tetrapage::geometry::internal {

// Both triangles cut the line L where their planes meet. Orient L by d = n1 x n2 (n the normal
// (v1 - v0) x (v2 - v0) of each triangle). Each triangle's cut is an interval of L whose ends
// are points X on an edge [u, w] of the triangle, with u strictly off the other plane (X may be
// w itself when w lies on that plane).
struct IntervalEnd {
  int off;    // u: the vertex strictly off the other plane
  int other;  // w
};

struct Interval {
  IntervalEnd lo, hi;
  bool single_point = false;  // the triangle touches the other plane at one vertex only
};

inline bool all_same_nonzero(const Sign s[3]) {
  return s[0] != Sign::zero && s[0] == s[1] && s[0] == s[2];
}
inline bool all_zero(const Sign s[3]) {
  return s[0] == Sign::zero && s[1] == Sign::zero && s[2] == Sign::zero;
}
inline bool straddles(const Sign s[3]) {
  const bool positive = s[0] == Sign::positive || s[1] == Sign::positive || s[2] == Sign::positive;
  const bool negative = s[0] == Sign::negative || s[1] == Sign::negative || s[2] == Sign::negative;
  return positive && negative;
}

// s: the signs of the triangle's vertices against the other plane (neither all zero nor all
// the same nonzero sign). first: this is the triangle whose normal comes first in d.
inline Interval cut_interval(const Sign s[3], bool first) {
  for (int i = 0; i < 3; ++i) {
    if (s[i] == Sign::zero) continue;
    const int j = i == 2 ? 0 : i + 1;
    const int k = j == 2 ? 0 : j + 1;
    if (s[j] == s[i] || s[k] == s[i]) continue;
    // Vertex i is alone on its side; the cut runs from edge (i, j) to edge (i, k). With the
    // vertices counterclockwise about the normal, the end on edge (i, j) is the upper end
    // along d for the first triangle when vertex i is on the positive side, and the lower end
    // for the second (d = n1 x n2 = -(n2 x n1)).
    const bool j_is_upper = (s[i] == Sign::positive) == first;
    const IntervalEnd on_j{i, j}, on_k{i, k};
    return {j_is_upper ? on_k : on_j, j_is_upper ? on_j : on_k, false};
  }
  // No lonely vertex: one vertex on the plane, the two others strictly on one side.
  const int z = s[0] == Sign::zero ? 0 : (s[1] == Sign::zero ? 1 : 2);
  const int o = z == 2 ? 0 : z + 1;
  return {{o, z}, {o, z}, true};
}

// The sign of (Y - X) . d for X an interval end of the first triangle and Y one of the second.
// With X on [u, w], Y on [s, t] (u off plane 2, t off plane 1), orient3d(u, w, s, t) is
// proportional to (Y - X) . d with the sign -side(u, plane 2) * side(t, plane 1).
inline Sign compare_along_line(const Triangle& a, const Sign sa[3], IntervalEnd x,
                               const Triangle& b, const Sign sb[3], IntervalEnd y) {
  return -(orient3d(a[x.off], a[x.other], b[y.other], b[y.off]) * sa[x.off] * sb[y.off]);
}

}  // namespace tetrapage::geometry::internal
