#pragma once
// Shared by the geometry kernel tests: a portable seeded generator, the adversarial input
// families (exact touching contacts built on integer lattices with dyadic barycentric
// coordinates, coplanar and near-coplanar pairs, slivers, needles, extreme scales and offsets),
// CGAL's exact-construction kernel (Epeck) as the oracle, and disagreement reporting.

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "tetrapage/runtime/geometry/Predicates.h"
#include "tetrapage/runtime/geometry/Shapes.h"

namespace tetrapage::geometry::testing {

using Epeck = CGAL::Exact_predicates_exact_constructions_kernel;

inline Epeck::Point_3 to_epeck(const Point& p) { return {p[0], p[1], p[2]}; }
inline Epeck::Triangle_3 to_epeck(const Triangle& t) {
  return {to_epeck(t[0]), to_epeck(t[1]), to_epeck(t[2])};
}
inline Epeck::Segment_3 to_epeck(const Segment& s) { return {to_epeck(s[0]), to_epeck(s[1])}; }
inline Epeck::Tetrahedron_3 to_epeck(const Tetrahedron& t) {
  return {to_epeck(t[0]), to_epeck(t[1]), to_epeck(t[2]), to_epeck(t[3])};
}

/// Epeck's verdict on non-degeneracy (the oracle's own preconditions).
inline bool epeck_degenerate(const Triangle& t) {
  return CGAL::collinear(to_epeck(t[0]), to_epeck(t[1]), to_epeck(t[2]));
}

/// Seeded and portable: mt19937_64 is fully specified, and the distributions are ours.
class Generator {
 public:
  explicit Generator(std::uint64_t seed) : engine_(seed) {}
  std::uint64_t bits() { return engine_(); }
  double uniform() { return double(engine_() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Integer in [lo, hi].
  std::int64_t integer(std::int64_t lo, std::int64_t hi) {
    return lo + std::int64_t(engine_() % std::uint64_t(hi - lo + 1));
  }
  bool coin() { return engine_() & 1; }
  /// Log-uniform magnitude in [10^lo, 10^hi].
  double log_uniform(double lo, double hi) { return std::pow(10.0, uniform(lo, hi)); }

 private:
  std::mt19937_64 engine_;
};

/// A transform that keeps exact constructions exact: permute and flip axes, scale by a power of
/// two, add an offset that is a multiple of the scale (small enough that every coordinate of a
/// lattice point, with up to `fraction_bits` bits after the point, still fits in 53 bits).
struct ExactTransform {
  int permutation[3] = {0, 1, 2};
  double flip[3] = {1, 1, 1};
  int exponent = 0;
  Point offset{0, 0, 0};

  Point operator()(const Point& p) const {
    Point out;
    for (int k = 0; k < 3; ++k)
      out[k] = std::ldexp(flip[k] * p[permutation[k]], exponent) + offset[k];
    return out;
  }
  template <std::size_t N>
  std::array<Point, N> operator()(const std::array<Point, N>& points) const {
    std::array<Point, N> out;
    for (std::size_t i = 0; i < N; ++i) out[i] = (*this)(points[i]);
    return out;
  }
};

/// Scales from about 1e-9 to 1e9 and offsets from 0 up to about 1e9, within what exactness
/// allows: lattice coordinates below 2^30 with up to fraction_bits bits after the point.
inline ExactTransform random_exact_transform(Generator& g, int fraction_bits = 20) {
  ExactTransform t;
  const int p = int(g.integer(0, 5));
  const int permutations[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int k = 0; k < 3; ++k) {
    t.permutation[k] = permutations[p][k];
    t.flip[k] = g.coin() ? 1.0 : -1.0;
  }
  t.exponent = int(g.integer(-52, 8));  // 2^-52 * 2^22 ~ 1e-9 .. 2^30 ~ 1e9
  // Every coordinate is a multiple of 2^(exponent - fraction_bits); the lattice part stays
  // below 2^(30 + fraction_bits) such units, so an offset below 2^51 units keeps the
  // sum within 53 bits.
  const double limit = std::ldexp(1.0, 51 + t.exponent - fraction_bits);
  const double unit = std::ldexp(1.0, t.exponent);  // offsets on the lattice itself
  const int kind = int(g.integer(0, 3));
  for (int k = 0; k < 3; ++k) {
    if (kind == 0) continue;  // a quarter of the cases at the origin
    // Aim at 1e6 .. 1e9 from the origin when the scale allows, else the largest exact offset.
    const double wanted = g.log_uniform(6, 9) * (g.coin() ? 1 : -1);
    const double value = std::fabs(wanted) < limit ? wanted : std::copysign(limit, wanted);
    t.offset[k] = std::round(value / unit) * unit;
  }
  return t;
}

/// A lattice point with coordinates in [-range, range].
inline Point lattice_point(Generator& g, std::int64_t range) {
  return {double(g.integer(-range, range)), double(g.integer(-range, range)),
          double(g.integer(-range, range))};
}

/// a + (i (b - a) + j (c - a)) / 2^bits, exact for lattice a, b, c.
inline Point dyadic_combination(const Point& a, const Point& b, const Point& c, std::int64_t i,
                                std::int64_t j, int bits) {
  Point out;
  for (int k = 0; k < 3; ++k)
    out[k] = a[k] + std::ldexp(double(i) * (b[k] - a[k]) + double(j) * (c[k] - a[k]), -bits);
  return out;
}

/// A random point of the closed triangle with dyadic barycentric coordinates (exact).
/// where: 0 interior, 1 an edge, 2 a vertex, 3 anywhere in its plane (maybe outside).
inline Point dyadic_point_on(Generator& g, const Triangle& t, int where, int bits = 8) {
  const std::int64_t n = std::int64_t(1) << bits;
  switch (where) {
    case 0: {
      const std::int64_t i = g.integer(1, n - 2);
      const std::int64_t j = g.integer(1, n - 1 - i);
      return dyadic_combination(t[0], t[1], t[2], i, j, bits);
    }
    case 1: {
      const int e = int(g.integer(0, 2));
      const Point& a = t[e];
      const Point& b = t[(e + 1) % 3];
      return dyadic_combination(a, b, b, g.integer(1, n - 1), 0, bits);
    }
    case 2: return t[g.integer(0, 2)];
    default:
      return dyadic_combination(t[0], t[1], t[2], g.integer(-n, 2 * n), g.integer(-n, 2 * n), bits);
  }
}

/// A random lattice triangle, sometimes a sliver (a vertex one unit off a long edge) or a
/// needle (one edge one unit long).
inline Triangle lattice_triangle(Generator& g, std::int64_t range) {
  Triangle t{lattice_point(g, range), lattice_point(g, range), lattice_point(g, range)};
  const int shape = int(g.integer(0, 9));
  if (shape == 0) {  // sliver
    t[2] = dyadic_combination(t[0], t[1], t[1], g.integer(0, 256), 0, 8);
    t[2][g.integer(0, 2)] += double(g.coin() ? 1 : -1);
  } else if (shape == 1) {  // needle
    t[2] = t[1];
    t[2][g.integer(0, 2)] += double(g.coin() ? 1 : -1);
  }
  return t;
}

/// Moves a coordinate by a few units in the last place.
inline Point nudge(Generator& g, Point p) {
  const int k = int(g.integer(0, 2));
  const int steps = int(g.integer(1, 3));
  for (int s = 0; s < steps; ++s)
    p[k] = std::nextafter(p[k], g.coin() ? INFINITY : -INFINITY);
  return p;
}

inline std::string hex(const Point& p) {
  char buffer[128];
  std::snprintf(buffer, sizeof buffer, "(%a, %a, %a)", p[0], p[1], p[2]);
  return buffer;
}
template <std::size_t N>
std::string hex(const std::array<Point, N>& points) {
  std::string out = "{";
  for (std::size_t i = 0; i < N; ++i) out += (i ? ", " : "") + hex(points[i]);
  return out + "}";
}

/// Collects disagreements with the oracle and reports the first few with their seeds.
class Disagreements {
 public:
  explicit Disagreements(std::string what) : what_(std::move(what)) {}
  void add(std::uint64_t seed, const std::string& detail) {
    ++count_;
    if (examples_.size() < 8)
      examples_.push_back("seed " + std::to_string(seed) + ": " + detail);
  }
  void expect_none(std::uint64_t cases) const {
    std::ostringstream out;
    out << what_ << ": " << count_ << " disagreements in " << cases << " cases";
    for (const auto& e : examples_) out << "\n  " << e;
    EXPECT_EQ(count_, 0u) << out.str();
  }
  std::uint64_t count() const { return count_; }

 private:
  std::string what_;
  std::uint64_t count_ = 0;
  std::vector<std::string> examples_;
};

/// A random rotation matrix applied to the point (not exact: for generic inputs).
struct Rotation {
  double m[9];
  Point operator()(const Point& p) const {
    return {m[0] * p[0] + m[1] * p[1] + m[2] * p[2], m[3] * p[0] + m[4] * p[1] + m[5] * p[2],
            m[6] * p[0] + m[7] * p[1] + m[8] * p[2]};
  }
};
inline Rotation random_rotation(Generator& g) {
  double q[4];
  double n2 = 0;
  do {
    n2 = 0;
    for (double& x : q) {
      x = g.uniform(-1, 1);
      n2 += x * x;
    }
  } while (n2 < 1e-3 || n2 > 1);
  const double s = 1 / std::sqrt(n2);
  const double w = q[0] * s, x = q[1] * s, y = q[2] * s, z = q[3] * s;
  return {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
           2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
           2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
}

}  // namespace tetrapage::geometry::testing
