#include "tetrapage/runtime/geometry/Predicates.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <utility>

namespace tetrapage::geometry {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;

Sign from_cgal(CGAL::Sign s) {
  return static_cast<Sign>(static_cast<int>(s));
}

// The exact sign of minuend - subtrahend (no subtraction, hence no rounding).
Sign difference_sign(double minuend, double subtrahend) {
  return minuend > subtrahend ? Sign::positive
                              : (minuend < subtrahend ? Sign::negative : Sign::zero);
}

}  // namespace

Sign orient3d_cgal(const Point& a, const Point& b, const Point& c, const Point& d) {
  return from_cgal(Kernel::Orientation_3()(
      Kernel::Point_3(a[0], a[1], a[2]), Kernel::Point_3(b[0], b[1], b[2]),
      Kernel::Point_3(c[0], c[1], c[2]), Kernel::Point_3(d[0], d[1], d[2])));
}

Sign orient2d_cgal(double ax, double ay, double bx, double by, double cx, double cy) {
  return from_cgal(Kernel::Orientation_2()(Kernel::Point_2(ax, ay), Kernel::Point_2(bx, by),
                                           Kernel::Point_2(cx, cy)));
}

Sign orient3d_sos(const Point& a, const Point& b, const Point& c, const Point& d,
                  std::uint64_t id_a, std::uint64_t id_b, std::uint64_t id_c, std::uint64_t id_d) {
  const Sign unperturbed = orient3d(a, b, c, d);
  if (unperturbed != Sign::zero) return unperturbed;

  // Rank the points by id (insertion sort, counting swaps for the permutation's parity).
  const Point* p[4] = {&a, &b, &c, &d};
  std::uint64_t id[4] = {id_a, id_b, id_c, id_d};
  bool odd = false;
  for (int i = 1; i < 4; ++i)
    for (int j = i; j > 0 && id[j - 1] > id[j]; --j) {
      std::swap(id[j - 1], id[j]);
      std::swap(p[j - 1], p[j]);
      odd = !odd;
    }
  if (id[0] == id[1] || id[1] == id[2] || id[2] == id[3]) return Sign::zero;
  const Point& p0 = *p[0];
  const Point& p1 = *p[1];
  const Point& p2 = *p[2];
  const Point& p3 = *p[3];

  // Coordinate k of the point of rank r moves by e^(2^(3r + k)). The determinant of the rows
  // (1, x, y, z) of the ranked points is then a polynomial in e; its lowest-order nonzero
  // coefficient gives the sign. In increasing order of the exponent, the coefficients are the
  // minors below (each the determinant with the perturbed rows replaced by unit vectors).
  auto decide = [&]() -> Sign {
    Sign s;
    if ((s = -normal_sign(p1, p2, p3, 0)) != Sign::zero) return s;    // e^1: p0.x
    if ((s = -normal_sign(p1, p2, p3, 1)) != Sign::zero) return s;    // e^2: p0.y
    if ((s = -normal_sign(p1, p2, p3, 2)) != Sign::zero) return s;    // e^4: p0.z
    if ((s = normal_sign(p0, p2, p3, 0)) != Sign::zero) return s;     // e^8: p1.x
    if ((s = difference_sign(p2[2], p3[2])) != Sign::zero) return s;  // p1.x, p0.y
    if ((s = difference_sign(p3[1], p2[1])) != Sign::zero) return s;  // p1.x, p0.z
    if ((s = normal_sign(p0, p2, p3, 1)) != Sign::zero) return s;     // p1.y
    if ((s = difference_sign(p3[2], p2[2])) != Sign::zero) return s;  // p1.y, p0.x
    if ((s = difference_sign(p2[0], p3[0])) != Sign::zero) return s;  // p1.y, p0.z
    if ((s = normal_sign(p0, p2, p3, 2)) != Sign::zero) return s;     // p1.z
    if ((s = difference_sign(p2[1], p3[1])) != Sign::zero) return s;  // p1.z, p0.x
    if ((s = difference_sign(p3[0], p2[0])) != Sign::zero) return s;  // p1.z, p0.y
    if ((s = -normal_sign(p0, p1, p3, 0)) != Sign::zero) return s;    // p2.x
    if ((s = difference_sign(p3[2], p1[2])) != Sign::zero) return s;  // p2.x, p0.y
    if ((s = difference_sign(p1[1], p3[1])) != Sign::zero) return s;  // p2.x, p0.z
    if ((s = difference_sign(p0[2], p3[2])) != Sign::zero) return s;  // p2.x, p1.y
    return Sign::positive;                                            // p2.x, p1.y, p0.z
  };
  const Sign ranked = decide();
  return odd ? -ranked : ranked;
}

}  // namespace tetrapage::geometry
