#include "tetrapage/runtime/geometry/TriangleContact.h"

#include <CGAL/Gmpq.h>
#include <CGAL/Mpzf.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>

#include "CoplanarTests.h"
#include "PlaneCut.h"
#include "tetrapage/runtime/geometry/Predicates.h"
#include "tetrapage/runtime/geometry/SegmentTriangle.h"

namespace tetrapage::geometry {
namespace {

using internal::Point2;

// A determinant computed in double by expansion of minors, with what bounds its error:
// |value - exact| <= bound + 2^-1072 underflow_units (DeterminantFilter.h).
struct Estimate {
  double value;
  double bound;
  double underflow_units;
};

// The accuracy asked of the determinants that place a point: their errors together below
// 2^-42 of their magnitudes. Tighter asks for the exact fallback too often (the filter's bound
// is 8u times the permanent, which is often 10 to 100 times the determinant).
constexpr double kDeterminantAccuracy = 0x1p-42;

// The errors together are below kDeterminantAccuracy * magnitude: filter_accepts(x, ...)
// checks that each of the two error terms is below x / 2.
bool accurate_enough(std::initializer_list<Estimate> values, double magnitude) {
  double bound = 0, units = 0;
  for (const Estimate& e : values) {
    bound += e.bound;
    units += e.underflow_units;
  }
  return detail::filter_accepts(magnitude * kDeterminantAccuracy, 1.0, bound, units);
}

// det[b - a, c - a, d - a], the value whose sign orient3d gives.
Estimate orient3d_estimate(const Point& a, const Point& b, const Point& c, const Point& d) {
  const double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
  const double vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
  const double wx = d[0] - a[0], wy = d[1] - a[1], wz = d[2] - a[2];
  const double p1 = uy * vz, p2 = uz * vy, p3 = uz * vx, p4 = ux * vz, p5 = ux * vy, p6 = uy * vx;
  const double det = wx * (p1 - p2) + wy * (p3 - p4) + wz * (p5 - p6);
  const double awx = std::fabs(wx), awy = std::fabs(wy), awz = std::fabs(wz);
  const double permanent = awx * (std::fabs(p1) + std::fabs(p2)) +
                           awy * (std::fabs(p3) + std::fabs(p4)) +
                           awz * (std::fabs(p5) + std::fabs(p6));
  return {det, detail::kOrient3dRelativeBound * permanent, awx + awy + awz + 2};
}

// The exact fallback: Mpzf holds every sum and product of doubles exactly, without the gcd
// of a rational (slow for tiny coordinates, whose denominators reach 2^1074); only the ratio
// t goes through a rational, so that it is exact before its rounding even when the
// determinants lie below the range of double.
using CGAL::Mpzf;

Mpzf orient3d_exact(const Point& a, const Point& b, const Point& c, const Point& d) {
  auto diff = [](double x, double y) { return Mpzf(x) - Mpzf(y); };
  const Mpzf ux = diff(b[0], a[0]), uy = diff(b[1], a[1]), uz = diff(b[2], a[2]);
  const Mpzf vx = diff(c[0], a[0]), vy = diff(c[1], a[1]), vz = diff(c[2], a[2]);
  const Mpzf wx = diff(d[0], a[0]), wy = diff(d[1], a[1]), wz = diff(d[2], a[2]);
  return wx * (uy * vz - uz * vy) + wy * (uz * vx - ux * vz) + wz * (ux * vy - uy * vx);
}

// x / y rounded to double (within 2u relative), y nonzero.
double exact_ratio(const Mpzf& x, const Mpzf& y) {
  return CGAL::to_double(CGAL::Gmpq(x) / CGAL::Gmpq(y));
}

// (b - a) x (c - a) for 2D points, the value whose sign orient2d gives.
Estimate orient2d_estimate(const Point2& a, const Point2& b, const Point2& c) {
  const double left = (b.x - a.x) * (c.y - a.y), right = (b.y - a.y) * (c.x - a.x);
  return {left - right, detail::kOrient2dRelativeBound * (std::fabs(left) + std::fabs(right)), 2};
}

Mpzf orient2d_exact(const Point2& a, const Point2& b, const Point2& c) {
  return (Mpzf(b.x) - Mpzf(a.x)) * (Mpzf(c.y) - Mpzf(a.y)) -
         (Mpzf(b.y) - Mpzf(a.y)) * (Mpzf(c.x) - Mpzf(a.x));
}

// The point of [v, w] where an affine function f vanishes, f(v) and f(w) nonzero of opposite
// signs: v + t (w - v) with t = |f(v)| / (|f(v)| + |f(w)|), in [0, 1] whatever the rounding.
// With both values within 2^-42 (|f(v)| + |f(w)|) of the exact ones, |t - t*| <= 2^-42 + 2u
// (t(a, b) - t(a*, b*) = (a b* - a* b) / ((a + b)(a* + b*)), exactly).
Point at_parameter(const Point& v, const Point& w, double t) {
  return {v[0] + t * (w[0] - v[0]), v[1] + t * (w[1] - v[1]), v[2] + t * (w[2] - v[2])};
}
Point zero_on_edge(const Point& v, const Point& w, double fv, double fw) {
  return at_parameter(v, w, std::fabs(fv) / (std::fabs(fv) + std::fabs(fw)));
}
// The same with exact values: t exact, then rounded (within 2u relative).
Point zero_on_edge(const Point& v, const Point& w, const Mpzf& fv, const Mpzf& fw) {
  const Mpzf a = CGAL::abs(fv), b = CGAL::abs(fw);
  return at_parameter(v, w, exact_ratio(a, a + b));
}

// Edge [v, w] of one triangle crossing the plane of `plane`.
Point crossing_of_plane(const Point& v, const Point& w, const Triangle& plane) {
  const Estimate fv = orient3d_estimate(plane[0], plane[1], plane[2], v);
  const Estimate fw = orient3d_estimate(plane[0], plane[1], plane[2], w);
  if (accurate_enough({fv, fw}, std::fabs(fv.value) + std::fabs(fw.value)))
    return zero_on_edge(v, w, fv.value, fw.value);
  return zero_on_edge(v, w, orient3d_exact(plane[0], plane[1], plane[2], v),
                      orient3d_exact(plane[0], plane[1], plane[2], w));
}

// Segment [v, w] crossing the line (r, s), in the projection `flat` of their common plane
// (the ratio of the two determinants is the same in the plane and in the projection).
Point crossing_of_line(const Point& v, const Point& w, const Point2& fv2, const Point2& fw2,
                       const Point2& r, const Point2& s) {
  const Estimate fv = orient2d_estimate(r, s, fv2), fw = orient2d_estimate(r, s, fw2);
  if (accurate_enough({fv, fw}, std::fabs(fv.value) + std::fabs(fw.value)))
    return zero_on_edge(v, w, fv.value, fw.value);
  return zero_on_edge(v, w, orient2d_exact(r, s, fv2), orient2d_exact(r, s, fw2));
}

Vec3 unit_normal(const Triangle& t) {
  // Component k is the orientation of the projection along k (see normal_sign), computed
  // within 2^-42 of the largest in all, so the direction is accurate even for slivers.
  std::array<Point2, 3> p[3];
  std::array<Estimate, 3> e;
  for (int axis = 0; axis < 3; ++axis) {
    p[axis] = internal::project(t, axis);
    e[axis] = orient2d_estimate(p[axis][0], p[axis][1], p[axis][2]);
  }
  Vec3 n{e[0].value, e[1].value, e[2].value};
  if (!accurate_enough({e[0], e[1], e[2]},
                       std::max({std::fabs(n[0]), std::fabs(n[1]), std::fabs(n[2])}))) {
    // Exactly, divided by the largest magnitude before rounding (the components may lie
    // below the range of double).
    std::array<Mpzf, 3> exact;
    for (int axis = 0; axis < 3; ++axis)
      exact[axis] = orient2d_exact(p[axis][0], p[axis][1], p[axis][2]);
    const Mpzf largest = std::max({CGAL::abs(exact[0]), CGAL::abs(exact[1]), CGAL::abs(exact[2])});
    if (CGAL::is_zero(largest)) return {0, 0, 0};
    for (int axis = 0; axis < 3; ++axis) n[axis] = exact_ratio(exact[axis], largest);
  }
  const double largest = std::max({std::fabs(n[0]), std::fabs(n[1]), std::fabs(n[2])});
  if (largest == 0) return {0, 0, 0};
  for (double& x : n) x /= largest;  // no overflow nor underflow in the squares
  const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  for (double& x : n) x /= length;
  return n;
}

void add_point(ContactGeometry& out, const Point& p) {
  out.points[out.count++] = p;
}

void set_shape_from_count(ContactGeometry& out) {
  out.shape = out.count == 0   ? ContactShape::none
              : out.count == 1 ? ContactShape::point
              : out.count == 2 ? ContactShape::segment
                               : ContactShape::polygon;
}

// ---- Not coplanar: the overlap of the two cuts along the common line ----------------------

// The point of an interval end: the edge [off, other] of t crossing the other triangle's plane.
Point cut_point(const Triangle& t, const Sign s[3], internal::IntervalEnd end,
                const Triangle& plane) {
  if (s[end.other] == Sign::zero) return t[end.other];
  return crossing_of_plane(t[end.off], t[end.other], plane);
}

// a and b proper and not coplanar, sa and sb their vertices' sides of the other plane (each
// straddling or touching). The contact is [max(lo a, lo b), min(hi a, hi b)] along
// d = n_a x n_b, ends compared exactly.
void crossing_contact(const Triangle& a, const Sign sa[3], const Triangle& b, const Sign sb[3],
                      ContactGeometry& out) {
  using internal::compare_along_line;
  const internal::Interval ia = internal::cut_interval(sa, true);
  const internal::Interval ib = internal::cut_interval(sb, false);
  const Sign gap_low = compare_along_line(a, sa, ia.lo, b, sb, ib.hi);  // hi(b) - lo(a)
  if (gap_low == Sign::negative) return;
  const Sign gap_high = compare_along_line(a, sa, ia.hi, b, sb, ib.lo);  // lo(b) - hi(a)
  if (gap_high == Sign::positive) return;
  const bool start_on_b = compare_along_line(a, sa, ia.lo, b, sb, ib.lo) == Sign::positive;
  const bool end_on_b = compare_along_line(a, sa, ia.hi, b, sb, ib.hi) == Sign::negative;
  // The chosen ends coincide when one interval is a point, or when the two meet end to end.
  const bool single = start_on_b == end_on_b ? (start_on_b ? ib.single_point : ia.single_point)
                      : start_on_b           ? gap_high == Sign::zero  // [lo b, hi a]
                                             : gap_low == Sign::zero;            // [lo a, hi b]
  add_point(out, start_on_b ? cut_point(b, sb, ib.lo, a) : cut_point(a, sa, ia.lo, b));
  if (!single) add_point(out, end_on_b ? cut_point(b, sb, ib.hi, a) : cut_point(a, sa, ia.hi, b));
  set_shape_from_count(out);
}

// ---- In one plane: a convex point, segment or triangle against another ---------------------

// One of the convex pieces: a point (n = 1), a segment (2) or a proper triangle (3).
struct Piece {
  std::array<Point, 3> v;
  int n = 0;
};

// Everything in the plane is decided on the projection along `axis`, injective on it.
class PlanarContact {
 public:
  PlanarContact(const Piece& p, const Piece& q, int axis) : p_(p), q_(q), axis_(axis) {}

  // The corners of p n q: vertices of either inside the other, and the crossings of an edge
  // interior of p with one of q. They are exactly the extreme points of the intersection
  // (vertices are extreme in their own piece; a proper crossing is where two boundary lines
  // of different directions meet), distinct but for equal vertices, which are merged.
  void collect() {
    for (int i = 0; i < p_.n; ++i)
      if (contains(q_, p_.v[i])) add(p_.v[i]);
    for (int j = 0; j < q_.n; ++j)
      if (contains(p_, q_.v[j])) add(q_.v[j]);
    for (int i = 0; i < edges(p_); ++i)
      for (int j = 0; j < edges(q_); ++j) add_crossing(p_, i, q_, j);
  }

  // Writes the corners; a polygon in the order whose projected orientation is
  // `counterclockwise`.
  void write(Sign counterclockwise, ContactGeometry& out) const {
    std::array<int, kMax> order{};
    for (int i = 0; i < count_; ++i) order[i] = i;
    if (count_ >= 3) sort_around(counterclockwise, order);
    for (int i = 0; i < std::min(count_, 6); ++i) add_point(out, found_[order[i]]);
    set_shape_from_count(out);
  }

 private:
  static constexpr int kMax = 15;  // 3 + 3 vertices and 9 crossings; at most 6 are corners

  static int edges(const Piece& piece) { return piece.n == 3 ? 3 : piece.n - 1; }
  static int next(const Piece& piece, int i) { return i + 1 == piece.n ? 0 : i + 1; }

  Point2 flat(const Point& x) const { return internal::project(x, axis_); }
  Sign orient(const Point& a, const Point& b, const Point& c) const {
    return internal::orient(flat(a), flat(b), flat(c));
  }

  bool contains(const Piece& piece, const Point& x) const {
    if (piece.n == 1) return piece.v[0] == x;
    if (piece.n == 2)
      return orient(piece.v[0], piece.v[1], x) == Sign::zero &&
             internal::collinear_segments_overlap(piece.v[0], piece.v[1], x, x);
    const Sign orientation = orient(piece.v[0], piece.v[1], piece.v[2]);
    for (int i = 0; i < 3; ++i)
      if (orient(piece.v[i], piece.v[next(piece, i)], x) == -orientation) return false;
    return true;
  }

  // Edge i of a and edge j of b cross at a point interior to both (all four signs nonzero).
  void add_crossing(const Piece& a, int i, const Piece& b, int j) {
    const Point& p = a.v[i];
    const Point& q = a.v[next(a, i)];
    const Point& r = b.v[j];
    const Point& s = b.v[next(b, j)];
    const Sign op = orient(r, s, p), oq = orient(r, s, q);
    if (op == Sign::zero || oq != -op) return;
    const Sign orr = orient(p, q, r), os = orient(p, q, s);
    if (orr == Sign::zero || os != -orr) return;
    // orient(r, s, x) is affine in x: its zero on [p, q] is the crossing.
    found_[count_++] = crossing_of_line(p, q, flat(p), flat(q), flat(r), flat(s));
  }

  void add(const Point& x) {
    for (int k = 0; k < count_; ++k)
      if (found_[k] == x) return;
    found_[count_++] = x;
  }

  // The corners are in convex position; `counterclockwise` is the projected orientation of a
  // counterclockwise turn about the first triangle's normal. Monotone chains: from the lowest
  // corner (x, then y) to the highest, the ones below that diagonal by increasing x, then
  // those above by decreasing x. Corners closer than the rounding error may swap, nothing
  // more (an angle about a centre, or from a corner, can misorder corners far apart).
  void sort_around(Sign counterclockwise, std::array<int, kMax>& order) const {
    std::sort(order.begin(), order.begin() + count_, [&](int i, int j) {
      const Point2 a = flat(found_[i]), b = flat(found_[j]);
      return a.x < b.x || (a.x == b.x && a.y < b.y);
    });
    const Point2 lo = flat(found_[order[0]]), hi = flat(found_[order[count_ - 1]]);
    std::array<int, kMax> cycle{};
    int n = 0;
    cycle[n++] = order[0];
    for (int i = 1; i + 1 < count_; ++i)
      if (internal::orient(lo, hi, flat(found_[order[i]])) != Sign::positive) cycle[n++] = order[i];
    cycle[n++] = order[count_ - 1];
    for (int i = count_ - 2; i > 0; --i)
      if (internal::orient(lo, hi, flat(found_[order[i]])) == Sign::positive) cycle[n++] = order[i];
    if (counterclockwise == Sign::negative) std::reverse(cycle.begin() + 1, cycle.begin() + n);
    order = cycle;
  }

  const Piece& p_;
  const Piece& q_;
  int axis_;
  std::array<Point, kMax> found_{};
  int count_ = 0;
};

// counterclockwise: the projected orientation of the first triangle (a polygon is ordered
// counterclockwise about its normal); any sign when a piece is not a triangle (no polygon).
void planar_contact(const Piece& p, const Piece& q, int axis, Sign counterclockwise,
                    ContactGeometry& out) {
  PlanarContact contact(p, q, axis);
  contact.collect();
  contact.write(counterclockwise, out);
}

// ---- Degenerate triangles --------------------------------------------------------------------

// A triangle with collinear vertices as the segment (or point) they span: its extreme
// vertices in lexicographic order, which is the order along the line.
Piece as_piece(const Triangle& t) {
  const auto [lo, hi] = std::minmax_element(t.begin(), t.end(), internal::lexicographically_less);
  if (*lo == *hi) return {{*lo, *lo, *lo}, 1};
  return {{*lo, *hi, *hi}, 2};
}

// A point or segment s against the proper triangle t (plane side tests first).
void piece_against_triangle(const Piece& s, const Triangle& t, ContactGeometry& out) {
  const OrientedPlane plane(t);
  const Sign sp = plane.side(s.v[0]), sq = s.n == 1 ? sp : plane.side(s.v[1]);
  if (sp != Sign::zero && sp == sq) return;
  if (sp == Sign::zero && sq == Sign::zero) {
    const int axis = internal::injective_axis(t[0], t[1], t[2]);
    planar_contact(s, {t, 3}, axis, Sign::positive, out);
    return;
  }
  // The segment crosses the plane at one point.
  if (!segment_intersects_triangle({s.v[0], s.v[1]}, t)) return;
  if (sp == Sign::zero) {
    add_point(out, s.v[0]);
  } else if (sq == Sign::zero) {
    add_point(out, s.v[1]);
  } else {
    add_point(out, crossing_of_plane(s.v[0], s.v[1], t));
  }
  set_shape_from_count(out);
}

// Two points or segments.
void piece_against_piece(const Piece& p, const Piece& q, ContactGeometry& out) {
  const Point* all[4] = {&p.v[0], &p.v[p.n - 1], &q.v[0], &q.v[q.n - 1]};
  if (orient3d(*all[0], *all[1], *all[2], *all[3]) != Sign::zero) return;  // skew
  // A projection injective on their plane, or, all on one line, on that line.
  for (int k = 0; k < 4; ++k) {
    const int axis = internal::injective_axis(*all[k % 4], *all[(k + 1) % 4], *all[(k + 2) % 4]);
    if (axis >= 0) return planar_contact(p, q, axis, Sign::positive, out);
  }
  Point lo = *all[0], hi = *all[0];
  for (const Point* x : all) {
    if (internal::lexicographically_less(*x, lo)) lo = *x;
    if (internal::lexicographically_less(hi, *x)) hi = *x;
  }
  int axis = 0;  // the coordinate along which the line varies least keeps the others
  for (int k = 1; k < 3; ++k)
    if (std::fabs(hi[k] - lo[k]) < std::fabs(hi[axis] - lo[axis])) axis = k;
  planar_contact(p, q, axis, Sign::positive, out);
}

void degenerate_contact(const Triangle& a, bool a_proper, const Triangle& b, bool b_proper,
                        ContactGeometry& out) {
  if (a_proper) return piece_against_triangle(as_piece(b), a, out);
  if (b_proper) return piece_against_triangle(as_piece(a), b, out);
  piece_against_piece(as_piece(a), as_piece(b), out);
}

}  // namespace

ContactGeometry contact_geometry(const Triangle& first, const Triangle& second) {
  ContactGeometry out;
  out.first_normal = unit_normal(first);
  out.second_normal = unit_normal(second);
  // The same decisions as TriangleTriangle.cpp's intersect(), in the same order.
  const OrientedPlane plane_b(second);
  Sign sa[3];
  for (int i = 0; i < 3; ++i) sa[i] = plane_b.side(first[i]);
  if (internal::all_same_nonzero(sa)) return out;
  const OrientedPlane plane_a(first);
  Sign sb[3];
  for (int i = 0; i < 3; ++i) sb[i] = plane_a.side(second[i]);
  if (internal::all_same_nonzero(sb)) return out;
  if (!internal::all_zero(sa) && !internal::all_zero(sb)) {
    crossing_contact(first, sa, second, sb, out);
    return out;
  }
  const int axis_a = internal::injective_axis(first[0], first[1], first[2]);
  const int axis_b = internal::injective_axis(second[0], second[1], second[2]);
  if (axis_a < 0 || axis_b < 0) {
    degenerate_contact(first, axis_a >= 0, second, axis_b >= 0, out);
    return out;
  }
  out.coplanar = true;
  planar_contact({first, 3}, {second, 3}, axis_a, normal_sign(first[0], first[1], first[2], axis_a),
                 out);
  return out;
}

}  // namespace tetrapage::geometry
