#include "tetrapage/runtime/geometry/TriangleDistance.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "tetrapage/runtime/geometry/Box.h"
#include "tetrapage/runtime/geometry/TriangleTriangle.h"

namespace tetrapage::geometry {
namespace {

constexpr double kUnit = 0x1p-53;  // u, the unit roundoff of double

using Vector = std::array<double, 3>;

Vector sub(const Vector& a, const Vector& b) {
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
Vector add_scaled(const Vector& a, double s, const Vector& d) {
  return {a[0] + s * d[0], a[1] + s * d[1], a[2] + s * d[2]};
}
double dot(const Vector& a, const Vector& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
double norm(const Vector& a) {
  return std::sqrt(dot(a, a));
}
Vector cross(const Vector& a, const Vector& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

struct Candidate {
  double squared = std::numeric_limits<double>::infinity();
  Vector on_first{}, on_second{};
  void offer(const Vector& x, const Vector& y) {
    const Vector d = sub(y, x);
    const double s = dot(d, d);
    if (s < squared) {
      squared = s;
      on_first = x;
      on_second = y;
    }
  }
};

// Every reported point is a + s (b - a) or a + s ab + t ac with parameters clamped to the
// segment or triangle, so it lies within a few roundings of a true point of the shape.
Vector closest_on_segment(const Vector& p, const Vector& a, const Vector& b) {
  const Vector ab = sub(b, a);
  const double length2 = dot(ab, ab);
  if (!(length2 > 0)) return a;
  const double s = std::clamp(dot(sub(p, a), ab) / length2, 0.0, 1.0);
  return add_scaled(a, s, ab);
}

Vector closest_on_triangle(const Vector& p, const std::array<Vector, 3>& t) {
  const Vector ab = sub(t[1], t[0]), ac = sub(t[2], t[0]), ap = sub(p, t[0]);
  const double d00 = dot(ab, ab), d01 = dot(ab, ac), d11 = dot(ac, ac);
  const double d20 = dot(ap, ab), d21 = dot(ap, ac);
  const double denominator = d00 * d11 - d01 * d01;
  if (denominator > 1e-12 * d00 * d11) {
    const double beta = (d11 * d20 - d01 * d21) / denominator;
    const double gamma = (d00 * d21 - d01 * d20) / denominator;
    if (beta >= 0 && gamma >= 0 && beta + gamma <= 1)  // the projection is inside
      return add_scaled(add_scaled(t[0], beta, ab), gamma, ac);
  }
  Vector best = closest_on_segment(p, t[0], t[1]);
  double best_squared = dot(sub(p, best), sub(p, best));
  for (int e = 1; e < 3; ++e) {
    const Vector x = closest_on_segment(p, t[e], t[e == 2 ? 0 : e + 1]);
    const double s = dot(sub(p, x), sub(p, x));
    if (s < best_squared) {
      best_squared = s;
      best = x;
    }
  }
  return best;
}

// The closest points of two segments when both lie strictly inside them (the other cases are
// vertex/triangle cases). Skips near-parallel pairs, whose minimum is also at an endpoint.
void offer_edge_pair(const Vector& p, const Vector& p2, const Vector& q, const Vector& q2,
                     Candidate& best) {
  const Vector d1 = sub(p2, p), d2 = sub(q2, q), r = sub(p, q);
  const double a = dot(d1, d1), e = dot(d2, d2), b = dot(d1, d2);
  const double c = dot(d1, r), f = dot(d2, r);
  const double denominator = a * e - b * b;
  if (!(denominator > 1e-12 * a * e)) return;
  const double s = (b * f - c * e) / denominator;
  const double t = (a * f - b * c) / denominator;
  if (s < 0 || s > 1 || t < 0 || t > 1) return;
  best.offer(add_scaled(p, s, d1), add_scaled(q, t, d2));
}

// The pair moved to a[0] and, when its extent is far from 1, scaled by a power of two (exact)
// to near 1: the solvers multiply up to four lengths, which overflow beyond 2^255 and
// underflow below 2^-255 and would drop the face and edge cases.
struct Translated {
  std::array<Vector, 3> a, b;
  double magnitude;    // M: bounds every translated coordinate and every |v - origin| coordinate
  double unscale = 1;  // the power of two back to world units
};

Translated translate(const Triangle& a, const Triangle& b) {
  Translated out;
  double m = 0;
  for (int i = 0; i < 3; ++i) {
    out.a[i] = sub(a[i], a[0]);
    out.b[i] = sub(b[i], a[0]);
    for (int k = 0; k < 3; ++k) m = std::max({m, std::fabs(out.a[i][k]), std::fabs(out.b[i][k])});
  }
  if (m > 0x1p200 || (m > 0 && m < 0x1p-200)) {
    const int exponent = std::ilogb(m);
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) {
        out.a[i][k] = std::ldexp(out.a[i][k], -exponent);
        out.b[i][k] = std::ldexp(out.b[i][k], -exponent);
      }
    m = std::ldexp(m, -exponent);
    out.unscale = std::ldexp(1.0, exponent);
  }
  out.magnitude = m * (1 + 4 * kUnit);
  return out;
}

// A rigorous lower bound on the true distance from the separation of the two triangles along
// the direction n: min over b of n.v - max over a of n.v, divided by |n|. Each computed dot
// product is within 7 u |n| M of the exact one on the untranslated vertices (translation and
// dot rounding), so the computed gap is within 18 u |n| M; 24 u |n| M covers it with room.
// Returned in world units (the scaling is exact).
double separation_lower_bound(const Translated& t, const Vector& n) {
  const double length = norm(n);
  if (!(length > 0) || !std::isfinite(length)) return 0.0;
  double max_a = -std::numeric_limits<double>::infinity();
  double min_b = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    max_a = std::max(max_a, dot(n, t.a[i]));
    min_b = std::min(min_b, dot(n, t.b[i]));
  }
  const double padded_length = length * (1 + 4 * kUnit);
  const double numerator = (min_b - max_a) - 24 * kUnit * padded_length * t.magnitude;
  if (!(numerator > 0)) return 0.0;
  return numerator / padded_length * (1 - 4 * kUnit) * t.unscale;
}

double clearance_upper_bound(double distance, double magnitude) {
  return distance * (1 + 4 * kUnit) + 128 * kUnit * magnitude;
}

}  // namespace

TriangleDistance triangle_distance(const Triangle& a, const Triangle& b) {
  TriangleDistance result;
  if (triangles_intersect(a, b)) {
    // Report a vertex of one triangle as both points only when exactness says "meet"; the
    // points are not needed by any caller in that case.
    result.on_first = result.on_second = a[0];
    return result;
  }
  const Translated t = translate(a, b);
  Candidate best;
  for (int i = 0; i < 3; ++i) {
    best.offer(t.a[i], closest_on_triangle(t.a[i], t.b));
    best.offer(closest_on_triangle(t.b[i], t.a), t.b[i]);
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      offer_edge_pair(t.a[i], t.a[i == 2 ? 0 : i + 1], t.b[j], t.b[j == 2 ? 0 : j + 1], best);
  result.distance = std::sqrt(best.squared) * t.unscale;
  result.upper_bound = clearance_upper_bound(result.distance, t.magnitude * t.unscale);
  result.lower_bound =
      std::min(separation_lower_bound(t, sub(best.on_second, best.on_first)), result.distance);
  for (int k = 0; k < 3; ++k) {
    result.on_first[k] = best.on_first[k] * t.unscale + a[0][k];
    result.on_second[k] = best.on_second[k] * t.unscale + a[0][k];
  }
  return result;
}

bool farther_than_cheaply(const Triangle& a, const Triangle& b, double d, const Vector& axis) {
  // Separated boxes: fl(lo - hi) (1 - 2u) is below the true axis gap.
  const Box box_a = box_of(a), box_b = box_of(b);
  for (int k = 0; k < 3; ++k) {
    if ((box_b.lo[k] - box_a.hi[k]) * (1 - 2 * kUnit) > d) return true;
    if ((box_a.lo[k] - box_b.hi[k]) * (1 - 2 * kUnit) > d) return true;
  }
  const Translated t = translate(a, b);
  // The caller's axis (a search's last closest direction) separates most of its pairs.
  if (separation_lower_bound(t, axis) > d) return true;
  // The triangles' own planes often separate by more than d: cheap and rigorous.
  const Vector normal_a = cross(sub(t.a[1], t.a[0]), sub(t.a[2], t.a[0]));
  const Vector normal_b = cross(sub(t.b[1], t.b[0]), sub(t.b[2], t.b[0]));
  const Vector minus_a{-normal_a[0], -normal_a[1], -normal_a[2]};
  const Vector minus_b{-normal_b[0], -normal_b[1], -normal_b[2]};
  for (const Vector* n : {&normal_a, &minus_a, &normal_b, &minus_b})
    if (separation_lower_bound(t, *n) > d) return true;
  return false;
}

bool within_distance(const Triangle& a, const Triangle& b, double d) {
  return !farther_than_cheaply(a, b, d, {0, 0, 0}) && triangle_distance(a, b).lower_bound <= d;
}

bool triangle_outside_ball(const Triangle& triangle, const Point& centre, double radius) {
  const auto sub = [](const Point& x, const Point& y) {
    return Point{x[0] - y[0], x[1] - y[1], x[2] - y[2]};
  };
  const auto dot = [](const Point& x, const Point& y) {
    return x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
  };
  const Point& a = triangle[0];
  const Point& b = triangle[1];
  const Point& c = triangle[2];
  const Point ab = sub(b, a), ac = sub(c, a), ap = sub(centre, a);
  const double ab2 = dot(ab, ab), ac2 = dot(ac, ac), ap2 = dot(ap, ap);
  const double size = std::sqrt(ab2) + std::sqrt(ac2) + std::sqrt(ap2);
  // Rounding errors below are a few ulps of size^2 over the sine of the triangle's shape: far
  // inside the margin for a triangle whose largest angle's sine is at least 2^-10.
  const Point n{ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2],
                ab[0] * ac[1] - ab[1] * ac[0]};
  const Point bc = sub(c, b);
  const double longest2 = std::max({ab2, ac2, dot(bc, bc)});
  const double n2 = dot(n, n);
  // |n| = |ab||ac| sin A; the largest angle's sine is at least |n| / (longest side)^2.
  if (!(n2 >= 0x1p-20 * longest2 * longest2) || !(n2 > 0)) return false;
  const double reach = radius + 0x1p-20 * (size + radius);
  if (!(reach >= 0) || !std::isfinite(reach)) return false;
  const double limit = reach * reach;
  // The closest point's region: a vertex, an edge, or the face.
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return ap2 > limit;
  const Point bp = sub(centre, b);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return dot(bp, bp) > limit;
  const double vc = d1 * d4 - d3 * d2;
  const auto squared_to = [&](const Point& from, const Point& along, double t) {
    const Point d{from[0] - t * along[0], from[1] - t * along[1], from[2] - t * along[2]};
    return dot(d, d);
  };
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return squared_to(ap, ab, d1 / (d1 - d3)) > limit;
  const Point cp = sub(centre, c);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return dot(cp, cp) > limit;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return squared_to(ap, ac, d2 / (d2 - d6)) > limit;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0)
    return squared_to(bp, bc, (d4 - d3) / ((d4 - d3) + (d5 - d6))) > limit;
  // Inside the face's prism: the distance to the plane.
  const double plane = dot(n, ap);
  return plane * plane > limit * n2;
}

}  // namespace tetrapage::geometry
