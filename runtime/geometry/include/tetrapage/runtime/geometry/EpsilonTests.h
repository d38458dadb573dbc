#pragma once
/// @file EpsilonTests.h
/// The classic floating-point versions of the primitives, in float or double, with epsilon
/// thresholds: Moeller's triangle/triangle test (1997), Moeller and Trumbore's segment/triangle
/// test, Akenine-Moeller's triangle/box separating axis test, and orientation-based point in
/// tetrahedron. They are what the `float_eps` and `double_eps` accuracy modes run: fast, but
/// they may answer wrongly near contact (the benchmarks measure how often).
///
/// Coordinates are first taken relative to a local origin in double, then rounded to Real, so
/// that models far from the origin keep their precision. Epsilons are relative to the size of
/// the inputs: a value within relative_epsilon * (scale) of zero counts as zero.

#include <algorithm>
#include <cmath>

#include "tetrapage/runtime/geometry/Box.h"

namespace tetrapage::geometry::epsilon {

/// Default relative epsilons: a few thousand units in the last place of each type.
inline constexpr float kDefaultFloatEpsilon = 1e-5f;
inline constexpr double kDefaultDoubleEpsilon = 1e-12;

template <class Real>
using Vector = std::array<Real, 3>;

namespace detail {

template <class Real>
Vector<Real> relative(const Point& p, const Point& origin) {
  return {Real(p[0] - origin[0]), Real(p[1] - origin[1]), Real(p[2] - origin[2])};
}
template <class Real>
Vector<Real> sub(const Vector<Real>& a, const Vector<Real>& b) {
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
template <class Real>
Vector<Real> cross(const Vector<Real>& a, const Vector<Real>& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
template <class Real>
Real dot(const Vector<Real>& a, const Vector<Real>& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
template <class Real>
Real norm1(const Vector<Real>& a) {
  return std::fabs(a[0]) + std::fabs(a[1]) + std::fabs(a[2]);
}
template <class Real>
Real max_abs(const Vector<Real>& a) {
  return std::max({std::fabs(a[0]), std::fabs(a[1]), std::fabs(a[2])});
}

// The cut of one triangle with the other's plane, as an interval of the projections p onto
// the line direction; d are the signed distances to the other plane (zeroed when tiny).
// Returns false when all three distances are zero (coplanar).
template <class Real>
bool cut_interval(Real p0, Real p1, Real p2, Real d0, Real d1, Real d2, Real& lo, Real& hi) {
  auto cut = [&](Real pa, Real pb, Real pc, Real da, Real db, Real dc) {
    const Real x = pa + (pb - pa) * da / (da - db);
    const Real y = pa + (pc - pa) * da / (da - dc);
    lo = std::min(x, y);
    hi = std::max(x, y);
  };
  if (d0 * d1 > 0)
    cut(p2, p0, p1, d2, d0, d1);  // vertex 2 alone
  else if (d0 * d2 > 0)
    cut(p1, p0, p2, d1, d0, d2);  // vertex 1 alone
  else if (d1 * d2 > 0 || d0 != 0)
    cut(p0, p1, p2, d0, d1, d2);
  else if (d1 != 0)
    cut(p1, p0, p2, d1, d0, d2);
  else if (d2 != 0)
    cut(p2, p0, p1, d2, d0, d1);
  else
    return false;
  return true;
}

template <class Real>
Real orient2(Real ax, Real ay, Real bx, Real by, Real cx, Real cy) {
  return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
}

// Coplanar triangles, projected along their dominant normal axis: no edge separates them by
// more than the tolerance.
template <class Real>
bool coplanar_triangles_meet(const Vector<Real> a[3], const Vector<Real> b[3],
                             const Vector<Real>& normal, Real tolerance) {
  const Real nx = std::fabs(normal[0]), ny = std::fabs(normal[1]), nz = std::fabs(normal[2]);
  int i = 0, j = 1;
  if (nx >= ny && nx >= nz)
    i = 1, j = 2;
  else if (ny >= nz)
    i = 0, j = 2;
  auto separated = [&](const Vector<Real> s[3], const Vector<Real> o[3]) {
    const Real orientation = orient2(s[0][i], s[0][j], s[1][i], s[1][j], s[2][i], s[2][j]);
    const Real sign = orientation >= 0 ? Real(1) : Real(-1);
    for (int e = 0; e < 3; ++e) {
      const auto& p = s[e];
      const auto& q = s[e == 2 ? 0 : e + 1];
      bool all_out = true;
      for (int v = 0; v < 3 && all_out; ++v)
        all_out = sign * orient2(p[i], p[j], q[i], q[j], o[v][i], o[v][j]) < -tolerance;
      if (all_out) return true;
    }
    return false;
  };
  return !separated(a, b) && !separated(b, a);
}

}  // namespace detail

/// Moeller's interval test, in Real, with distances to the other plane below
/// relative_epsilon * |n|_1 * L treated as zero (L: the pair's coordinate magnitude).
template <class Real>
bool triangles_intersect(const Triangle& a, const Triangle& b, Real relative_epsilon) {
  using namespace detail;
  const Point& origin = a[0];
  const Vector<Real> va[3] = {relative<Real>(a[0], origin), relative<Real>(a[1], origin),
                              relative<Real>(a[2], origin)};
  const Vector<Real> vb[3] = {relative<Real>(b[0], origin), relative<Real>(b[1], origin),
                              relative<Real>(b[2], origin)};
  const Real scale =
      std::max({max_abs(va[1]), max_abs(va[2]), max_abs(vb[0]), max_abs(vb[1]), max_abs(vb[2])});

  const Vector<Real> n1 = cross(sub(va[1], va[0]), sub(va[2], va[0]));
  const Real offset1 = -dot(n1, va[0]);
  const Real tolerance1 = relative_epsilon * norm1(n1) * scale;
  Real db[3];
  for (int i = 0; i < 3; ++i) {
    db[i] = dot(n1, vb[i]) + offset1;
    if (std::fabs(db[i]) <= tolerance1) db[i] = 0;
  }
  if (db[0] * db[1] > 0 && db[0] * db[2] > 0) return false;

  const Vector<Real> n2 = cross(sub(vb[1], vb[0]), sub(vb[2], vb[0]));
  const Real offset2 = -dot(n2, vb[0]);
  const Real tolerance2 = relative_epsilon * norm1(n2) * scale;
  Real da[3];
  for (int i = 0; i < 3; ++i) {
    da[i] = dot(n2, va[i]) + offset2;
    if (std::fabs(da[i]) <= tolerance2) da[i] = 0;
  }
  if (da[0] * da[1] > 0 && da[0] * da[2] > 0) return false;

  // Project onto the coordinate axis closest to the direction of the planes' intersection line.
  const Vector<Real> direction = cross(n1, n2);
  const Real dx = std::fabs(direction[0]), dy = std::fabs(direction[1]),
             dz = std::fabs(direction[2]);
  const int axis = dx >= dy && dx >= dz ? 0 : (dy >= dz ? 1 : 2);
  Real lo_a, hi_a, lo_b, hi_b;
  if (!cut_interval(va[0][axis], va[1][axis], va[2][axis], da[0], da[1], da[2], lo_a, hi_a) ||
      !cut_interval(vb[0][axis], vb[1][axis], vb[2][axis], db[0], db[1], db[2], lo_b, hi_b))
    return coplanar_triangles_meet(va, vb, n1, relative_epsilon * scale * scale);
  return !(hi_a < lo_b || hi_b < lo_a);
}

/// Moeller and Trumbore's test for the segment [s0, s1]; a segment parallel to the plane
/// (within epsilon) counts as missing, as in the classic code.
template <class Real>
bool segment_intersects_triangle(const Segment& s, const Triangle& t, Real relative_epsilon) {
  using namespace detail;
  const Point& origin = t[0];
  const Vector<Real> p = relative<Real>(s[0], origin);
  const Vector<Real> direction = sub(relative<Real>(s[1], origin), p);
  const Vector<Real> e1 = relative<Real>(t[1], origin), e2 = relative<Real>(t[2], origin);
  const Vector<Real> h = cross(direction, e2);
  const Real determinant = dot(e1, h);
  if (std::fabs(determinant) <= relative_epsilon * max_abs(direction) * max_abs(e1) * max_abs(e2))
    return false;
  const Real inverse = Real(1) / determinant;
  const Vector<Real> sv{p[0], p[1], p[2]};  // p - v0, with v0 the origin
  const Real u = inverse * dot(sv, h);
  if (u < -relative_epsilon || u > 1 + relative_epsilon) return false;
  const Vector<Real> q = cross(sv, e1);
  const Real v = inverse * dot(direction, q);
  if (v < -relative_epsilon || u + v > 1 + relative_epsilon) return false;
  const Real along = inverse * dot(e2, q);
  return along >= -relative_epsilon && along <= 1 + relative_epsilon;
}

/// Akenine-Moeller's separating axis test of a triangle against a box, in Real, with a gap of
/// at most relative_epsilon * (scale) on an axis not counting as separation.
template <class Real>
bool triangle_intersects_box(const Triangle& t, const Box& box, Real relative_epsilon) {
  using namespace detail;
  if (box.empty()) return false;
  const Point center = box.center();
  const Vector<Real> half{Real(0.5 * (box.hi[0] - box.lo[0])), Real(0.5 * (box.hi[1] - box.lo[1])),
                          Real(0.5 * (box.hi[2] - box.lo[2]))};
  const Vector<Real> v[3] = {relative<Real>(t[0], center), relative<Real>(t[1], center),
                             relative<Real>(t[2], center)};
  const Real scale = std::max({max_abs(v[0]), max_abs(v[1]), max_abs(v[2]), max_abs(half)});
  const Real slack = relative_epsilon * scale;
  // The box's axes.
  for (int k = 0; k < 3; ++k) {
    const Real lo = std::min({v[0][k], v[1][k], v[2][k]});
    const Real hi = std::max({v[0][k], v[1][k], v[2][k]});
    if (lo > half[k] + slack || hi < -half[k] - slack) return false;
  }
  // The nine edge-by-axis products.
  const Vector<Real> edges[3] = {sub(v[1], v[0]), sub(v[2], v[1]), sub(v[0], v[2])};
  for (const auto& e : edges) {
    for (int k = 0; k < 3; ++k) {
      Vector<Real> axis{0, 0, 0};
      const int i = k == 2 ? 0 : k + 1, j = k == 0 ? 2 : k - 1;
      axis[i] = -e[j];  // unit(k) x e
      axis[j] = e[i];
      const Real p0 = dot(axis, v[0]), p1 = dot(axis, v[1]), p2 = dot(axis, v[2]);
      const Real radius = half[i] * std::fabs(axis[i]) + half[j] * std::fabs(axis[j]);
      const Real tolerance = slack * norm1(axis);
      if (std::min({p0, p1, p2}) > radius + tolerance ||
          std::max({p0, p1, p2}) < -radius - tolerance)
        return false;
    }
  }
  // The triangle's normal.
  const Vector<Real> normal = cross(edges[0], sub(v[2], v[0]));
  const Real distance = dot(normal, v[0]);
  const Real radius = half[0] * std::fabs(normal[0]) + half[1] * std::fabs(normal[1]) +
                      half[2] * std::fabs(normal[2]);
  return std::fabs(distance) <= radius + slack * norm1(normal);
}

/// Point in closed tetrahedron (either orientation) from Real orientation determinants, with
/// values within relative_epsilon * (scale) of zero counting as on the face.
template <class Real>
bool point_in_tetrahedron(const Point& p, const Tetrahedron& t, Real relative_epsilon) {
  using namespace detail;
  const Vector<Real> v[4] = {relative<Real>(t[0], p), relative<Real>(t[1], p),
                             relative<Real>(t[2], p), relative<Real>(t[3], p)};
  const Real scale = std::max({max_abs(v[0]), max_abs(v[1]), max_abs(v[2]), max_abs(v[3])});
  const Real tolerance = relative_epsilon * scale * scale * scale;
  // det[b - a, c - a, q - a] with q = 0 (the point is the origin).
  auto orient = [](const Vector<Real>& a, const Vector<Real>& b, const Vector<Real>& c) {
    return dot(cross(sub(b, a), sub(c, a)), Vector<Real>{-a[0], -a[1], -a[2]});
  };
  const Real volume = dot(cross(sub(v[1], v[0]), sub(v[2], v[0])), sub(v[3], v[0]));
  const Real sign = volume >= 0 ? Real(1) : Real(-1);
  return sign * orient(v[1], v[3], v[2]) >= -tolerance &&
         sign * orient(v[0], v[2], v[3]) >= -tolerance &&
         sign * orient(v[0], v[3], v[1]) >= -tolerance &&
         sign * orient(v[0], v[1], v[2]) >= -tolerance;
}

}  // namespace tetrapage::geometry::epsilon
