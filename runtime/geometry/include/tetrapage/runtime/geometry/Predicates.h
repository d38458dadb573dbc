#pragma once
/// @file Predicates.h
/// Exact orientation signs on the stored (double, or float widened to double) coordinates.
///
/// Every sign is exact. A floating-point filter with a proven error bound decides almost all
/// cases inline in a few nanoseconds; the rest go to CGAL's filtered exact predicates
/// (Exact_predicates_inexact_constructions_kernel), out of line. Because the signs are exact,
/// every caller that asks the same geometric question gets the same answer, whatever the order
/// of the arguments: that is what keeps mesh walks from looping.
///
/// Conventions (CGAL's): orient3d(a, b, c, d) is the sign of det[b - a, c - a, d - a], positive
/// when d lies on the side of the plane (a, b, c) that the normal (b - a) x (c - a) points to;
/// orient2d(a, b, c) is the sign of (b - a) x (c - a), positive for a left turn.
///
/// Ties (zero signs) are decided consistently by symbolic perturbation (Simulation of
/// Simplicity, Edelsbrunner and Muecke 1990): orient3d_sos perturbs every point by an
/// infinitesimal amount ranked by a global id; orient3d_perturbed_query perturbs only a query
/// point that is not a vertex of the mesh. Both never return zero on valid input.

#include <cmath>
#include <cstdint>

#include "tetrapage/formats/base/DeterminantFilter.h"
#include "tetrapage/runtime/geometry/Shapes.h"

namespace tetrapage::geometry {

/// The sign of a determinant.
enum class Sign : std::int8_t { negative = -1, zero = 0, positive = 1 };

constexpr Sign operator-(Sign s) {
  return static_cast<Sign>(-static_cast<int>(s));
}
constexpr Sign operator*(Sign a, Sign b) {
  return static_cast<Sign>(static_cast<int>(a) * static_cast<int>(b));
}
constexpr int to_int(Sign s) {
  return static_cast<int>(s);
}

/// The sign of a value (exact; NaN is treated as zero).
constexpr Sign sign_of(double x) {
  return x > 0 ? Sign::positive : (x < 0 ? Sign::negative : Sign::zero);
}

/// orient3d decided by CGAL's filtered exact predicate alone (no inline pre-filter).
/// Coordinates must be finite.
Sign orient3d_cgal(const Point& a, const Point& b, const Point& c, const Point& d);

/// orient2d decided by CGAL's filtered exact predicate alone (no inline pre-filter).
Sign orient2d_cgal(double ax, double ay, double bx, double by, double cx, double cy);

namespace detail {
using tetrapage::detail::filter_accepts;
using tetrapage::detail::kOrient2dRelativeBound;
using tetrapage::detail::kOrient3dRelativeBound;
}  // namespace detail

/// Exact sign of det[b - a, c - a, d - a] (finite coordinates).
inline Sign orient3d(const Point& a, const Point& b, const Point& c, const Point& d) {
  const double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
  const double vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
  const double wx = d[0] - a[0], wy = d[1] - a[1], wz = d[2] - a[2];
  const double p1 = uy * vz, p2 = uz * vy;
  const double p3 = uz * vx, p4 = ux * vz;
  const double p5 = ux * vy, p6 = uy * vx;
  const double det = wx * (p1 - p2) + wy * (p3 - p4) + wz * (p5 - p6);
  const double awx = std::fabs(wx), awy = std::fabs(wy), awz = std::fabs(wz);
  const double permanent = awx * (std::fabs(p1) + std::fabs(p2)) +
                           awy * (std::fabs(p3) + std::fabs(p4)) +
                           awz * (std::fabs(p5) + std::fabs(p6));
  if (detail::filter_accepts(std::fabs(det), detail::kOrient3dRelativeBound, permanent,
                             awx + awy + awz + 2))
    return sign_of(det);
  return orient3d_cgal(a, b, c, d);  // also reached on overflow (bound = inf) or NaN
}

/// Exact sign of (b - a) x (c - a) for 2D points (finite coordinates).
inline Sign orient2d(double ax, double ay, double bx, double by, double cx, double cy) {
  const double ux = bx - ax, uy = by - ay, vx = cx - ax, vy = cy - ay;
  const double left = ux * vy, right = uy * vx;
  const double det = left - right;
  if (detail::filter_accepts(std::fabs(det), detail::kOrient2dRelativeBound,
                             std::fabs(left) + std::fabs(right), 2))
    return sign_of(det);
  return orient2d_cgal(ax, ay, bx, by, cx, cy);
}

/// Exact sign of the component along `axis` (0, 1, 2) of the normal (b - a) x (c - a): the
/// orientation of the triangle projected along that axis onto the plane of the two other axes,
/// taken in cyclic order (y, z), (z, x), (x, y).
inline Sign normal_sign(const Point& a, const Point& b, const Point& c, int axis) {
  const int i = axis == 2 ? 0 : axis + 1;
  const int j = axis == 0 ? 2 : axis - 1;
  return orient2d(a[i], a[j], b[i], b[j], c[i], c[j]);
}

/// True when the three points are collinear (the triangle has zero area), exactly.
inline bool is_degenerate(const Point& a, const Point& b, const Point& c) {
  return normal_sign(a, b, c, 0) == Sign::zero && normal_sign(a, b, c, 1) == Sign::zero &&
         normal_sign(a, b, c, 2) == Sign::zero;
}
inline bool is_degenerate(const Triangle& t) {
  return is_degenerate(t[0], t[1], t[2]);
}

/// The plane of a triangle, prepared for many exact side tests: side(d) == orient3d(a, b, c, d)
/// with the normal computed once. The filter is the same as orient3d's.
class OrientedPlane {
 public:
  OrientedPlane(const Point& a, const Point& b, const Point& c) : a_(a), b_(b), c_(c) {
    const double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
    const double vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
    const double p1 = uy * vz, p2 = uz * vy;
    const double p3 = uz * vx, p4 = ux * vz;
    const double p5 = ux * vy, p6 = uy * vx;
    normal_ = {p1 - p2, p3 - p4, p5 - p6};
    magnitude_ = {std::fabs(p1) + std::fabs(p2), std::fabs(p3) + std::fabs(p4),
                  std::fabs(p5) + std::fabs(p6)};
  }
  explicit OrientedPlane(const Triangle& t) : OrientedPlane(t[0], t[1], t[2]) {}

  /// orient3d(a, b, c, d), exactly.
  Sign side(const Point& d) const {
    const double wx = d[0] - a_[0], wy = d[1] - a_[1], wz = d[2] - a_[2];
    const double det = wx * normal_[0] + wy * normal_[1] + wz * normal_[2];
    const double awx = std::fabs(wx), awy = std::fabs(wy), awz = std::fabs(wz);
    const double permanent = awx * magnitude_[0] + awy * magnitude_[1] + awz * magnitude_[2];
    if (detail::filter_accepts(std::fabs(det), detail::kOrient3dRelativeBound, permanent,
                               awx + awy + awz + 2))
      return sign_of(det);
    return orient3d_cgal(a_, b_, c_, d);
  }

 private:
  Point a_, b_, c_;
  std::array<double, 3> normal_;     ///< (b - a) x (c - a), rounded
  std::array<double, 3> magnitude_;  ///< the absolute values of its products, for the bound
};

/// Simulation of Simplicity: the sign of orient3d(a, b, c, d) after every point is moved by an
/// infinitesimal amount ranked by its id (a smaller id moves more). Equal to orient3d when that
/// is nonzero; never zero when the four ids are distinct. Consistent: permuting the points
/// together with their ids permutes the sign like a determinant.
/// Precondition: distinct ids (equal ids give zero).
Sign orient3d_sos(const Point& a, const Point& b, const Point& c, const Point& d,
                  std::uint64_t id_a, std::uint64_t id_b, std::uint64_t id_c, std::uint64_t id_d);

/// orient3d(a, b, c, q) with only the query point q perturbed, by (e, e^2, e^4) for an
/// infinitesimal e > 0 (the same as orient3d_sos with q ranked before every mesh vertex). Never
/// zero unless a, b, c are collinear. Needs no ids: the sign is antisymmetric in (a, b, c), so
/// two tetrahedra sharing the face see q on opposite sides.
inline Sign orient3d_perturbed_query(const Point& a, const Point& b, const Point& c,
                                     const Point& q) {
  const Sign s = orient3d(a, b, c, q);
  if (s != Sign::zero) return s;
  // d/dq of det[b - a, c - a, q - a] is the normal (b - a) x (c - a): its components decide.
  for (int axis = 0; axis < 3; ++axis) {
    const Sign n = normal_sign(a, b, c, axis);
    if (n != Sign::zero) return n;
  }
  return Sign::zero;
}

}  // namespace tetrapage::geometry
