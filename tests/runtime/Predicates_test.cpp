// The filtered orientation predicates against CGAL's exact-construction kernel, and the
// symbolic perturbation against a brute-force expansion of the perturbed determinant.

#include "tetrapage/runtime/geometry/Predicates.h"

#include <algorithm>
#include <map>

#include "GeometryTestSupport.h"

namespace tetrapage::geometry {
namespace {

using namespace testing;

Sign epeck_orient3d(const Point& a, const Point& b, const Point& c, const Point& d) {
  return static_cast<Sign>(int(CGAL::orientation(to_epeck(a), to_epeck(b), to_epeck(c), to_epeck(d))));
}

// Four points of one family; `family` picks the adversary.
std::array<Point, 4> orientation_case(Generator& g, int family) {
  switch (family) {
    case 0: {  // generic, any scale and offset
      const double scale = g.log_uniform(-9, 9);
      const double offset = g.coin() ? 0.0 : g.log_uniform(6, 9) * (g.coin() ? 1 : -1);
      std::array<Point, 4> p;
      for (auto& x : p)
        for (double& c : x) c = offset + scale * g.uniform(-1, 1);
      return p;
    }
    case 1:    // exactly coplanar, then maybe a few ulps off
    case 2: {  // exactly coplanar with the fourth point on an edge or a vertex
      const ExactTransform transform = random_exact_transform(g);
      const std::int64_t range = g.coin() ? 4 : (std::int64_t(1) << 20);
      Triangle t{lattice_point(g, range), lattice_point(g, range), lattice_point(g, range)};
      Point d = dyadic_point_on(g, t, family == 1 ? (g.coin() ? 0 : 3) : int(g.integer(1, 2)));
      std::array<Point, 4> p{transform(t[0]), transform(t[1]), transform(t[2]), transform(d)};
      if (family == 1 && g.coin()) p[g.integer(0, 3)] = nudge(g, p[g.integer(0, 3)]);
      return p;
    }
    case 3: {  // slivers: a long lattice edge and points one unit off it
      const ExactTransform transform = random_exact_transform(g);
      const std::int64_t range = std::int64_t(1) << 20;
      const Point a = lattice_point(g, range), b = lattice_point(g, range);
      Point c = dyadic_combination(a, b, b, g.integer(0, 256), 0, 8);
      Point d = dyadic_combination(a, b, b, g.integer(0, 256), 0, 8);
      c[g.integer(0, 2)] += double(g.integer(-1, 1));
      d[g.integer(0, 2)] += double(g.integer(-1, 1));
      return {transform(a), transform(b), transform(c), transform(d)};
    }
    case 4: {  // near underflow: tiny, subnormal-scale differences
      const int exponent = int(g.integer(-1074, -900));
      const Point base = g.coin() ? Point{0, 0, 0} : Point{g.uniform(-1, 1), g.uniform(-1, 1), 0};
      std::array<Point, 4> p;
      for (auto& x : p)
        for (int k = 0; k < 3; ++k) x[k] = base[k] + std::ldexp(double(g.integer(-8, 8)), exponent);
      return p;
    }
    case 5: {  // near overflow: huge coordinates
      const int exponent = int(g.integer(300, 1000));
      std::array<Point, 4> p;
      for (auto& x : p)
        for (double& c : x) c = std::ldexp(g.uniform(-1, 1), exponent);
      if (g.coin()) p[3] = p[g.integer(0, 2)];  // coincident points
      return p;
    }
    default: {  // repeated points and collinear triples
      const ExactTransform transform = random_exact_transform(g);
      std::array<Point, 4> p;
      for (auto& x : p) x = lattice_point(g, 2);
      p[g.integer(0, 3)] = p[g.integer(0, 3)];
      return transform(p);
    }
  }
}

TEST(Predicates, Orient3dMatchesEpeckOnAdversarialInputs) {
  constexpr int kFamilies = 7;
  constexpr std::uint64_t kCasesPerFamily = 150000;
  for (int family = 0; family < kFamilies; ++family) {
    Disagreements disagreements("orient3d family " + std::to_string(family));
    for (std::uint64_t c = 0; c < kCasesPerFamily; ++c) {
      const std::uint64_t seed = 1000003 * std::uint64_t(family) + c;
      Generator g(seed);
      const auto p = orientation_case(g, family);
      const Sign expected = epeck_orient3d(p[0], p[1], p[2], p[3]);
      const Sign got = orient3d(p[0], p[1], p[2], p[3]);
      // Any argument order is the same question: the signs must follow the permutation.
      const Sign swapped = orient3d(p[1], p[0], p[2], p[3]);
      const Sign rotated = orient3d(p[1], p[2], p[3], p[0]);
      const OrientedPlane plane(p[0], p[1], p[2]);
      if (got != expected || swapped != -expected || rotated != -expected ||
          plane.side(p[3]) != expected || orient3d_cgal(p[0], p[1], p[2], p[3]) != expected)
        disagreements.add(seed, hex(p) + " expected " + std::to_string(to_int(expected)) +
                                    " got " + std::to_string(to_int(got)));
    }
    disagreements.expect_none(kCasesPerFamily);
  }
}

TEST(Predicates, Orient2dMatchesEpeckOnAdversarialInputs) {
  constexpr std::uint64_t kCases = 600000;
  Disagreements disagreements("orient2d");
  for (std::uint64_t c = 0; c < kCases; ++c) {
    Generator g(c);
    const auto p = orientation_case(g, int(c % 7));
    // Drop one coordinate: the 2D question of the projected triangle.
    const int axis = int(c % 3);
    const Sign expected = static_cast<Sign>(int(CGAL::orientation(
        Epeck::Point_2(p[0][(axis + 1) % 3], p[0][(axis + 2) % 3]),
        Epeck::Point_2(p[1][(axis + 1) % 3], p[1][(axis + 2) % 3]),
        Epeck::Point_2(p[3][(axis + 1) % 3], p[3][(axis + 2) % 3]))));
    const Sign got = normal_sign(p[0], p[1], p[3], axis);
    if (got != expected) disagreements.add(c, hex(p) + " axis " + std::to_string(axis));
  }
  disagreements.expect_none(kCases);
}

// The perturbed determinant expanded by brute force: entry (row, coordinate k) of the point of
// id rank r is x + e^(2^(3r + k)); the rows are (1, x, y, z) in argument order; the sign of the
// lowest-order nonzero coefficient is the answer. Small integer coordinates keep it exact.
Sign sos_oracle(const std::array<std::array<std::int64_t, 3>, 4>& p,
                const std::array<std::uint64_t, 4>& id) {
  using Polynomial = std::map<int, std::int64_t>;  // exponent -> coefficient
  int rank[4];
  for (int i = 0; i < 4; ++i) {
    rank[i] = 0;
    for (int j = 0; j < 4; ++j) rank[i] += id[j] < id[i];
  }
  auto entry = [&](int row, int column) {
    if (column == 0) return Polynomial{{0, 1}};
    return Polynomial{{0, p[row][column - 1]}, {1 << (3 * rank[row] + column - 1), 1}};
  };
  Polynomial determinant;
  int sigma[4] = {0, 1, 2, 3};
  do {
    int inversions = 0;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) inversions += sigma[i] > sigma[j];
    Polynomial product{{0, inversions % 2 ? -1 : 1}};
    for (int row = 0; row < 4; ++row) {
      Polynomial next;
      for (const auto& [e1, c1] : product)
        for (const auto& [e2, c2] : entry(row, sigma[row])) next[e1 + e2] += c1 * c2;
      product = std::move(next);
    }
    for (const auto& [e, c] : product) determinant[e] += c;
  } while (std::next_permutation(sigma, sigma + 4));
  for (const auto& [e, c] : determinant)
    if (c != 0) return c > 0 ? Sign::positive : Sign::negative;
  return Sign::zero;
}

TEST(Predicates, SimulationOfSimplicityMatchesTheExpandedDeterminant) {
  constexpr std::uint64_t kCases = 40000;
  Disagreements disagreements("orient3d_sos");
  for (std::uint64_t c = 0; c < kCases; ++c) {
    Generator g(c);
    // Tiny grids give every degeneracy: coplanar, collinear, coincident points.
    const std::int64_t range = c % 4 == 0 ? 1 : 2;
    std::array<std::array<std::int64_t, 3>, 4> integer;
    std::array<Point, 4> p;
    for (int i = 0; i < 4; ++i)
      for (int k = 0; k < 3; ++k) {
        integer[i][k] = g.integer(-range, range);
        p[i][k] = double(integer[i][k]);
      }
    std::array<std::uint64_t, 4> id;
    for (auto& x : id) x = g.bits() % 1000;
    if (id[0] == id[1] || id[0] == id[2] || id[0] == id[3] || id[1] == id[2] || id[1] == id[3] ||
        id[2] == id[3])
      continue;
    const Sign expected = sos_oracle(integer, id);
    const Sign got = orient3d_sos(p[0], p[1], p[2], p[3], id[0], id[1], id[2], id[3]);
    const Sign swapped = orient3d_sos(p[1], p[0], p[2], p[3], id[1], id[0], id[2], id[3]);
    if (expected == Sign::zero || got != expected || swapped != -expected)
      disagreements.add(c, hex(p) + " ids " + std::to_string(id[0]) + "," + std::to_string(id[1]) +
                               "," + std::to_string(id[2]) + "," + std::to_string(id[3]) +
                               " expected " + std::to_string(to_int(expected)) + " got " +
                               std::to_string(to_int(got)));
  }
  disagreements.expect_none(kCases);
}

TEST(Predicates, PerturbedQueryIsSimulationOfSimplicityWithTheQueryFirst) {
  constexpr std::uint64_t kCases = 200000;
  Disagreements disagreements("orient3d_perturbed_query");
  for (std::uint64_t c = 0; c < kCases; ++c) {
    Generator g(c);
    const auto p = orientation_case(g, int(1 + c % 6));
    if (is_degenerate(p[0], p[1], p[2])) continue;
    const Sign expected = orient3d_sos(p[0], p[1], p[2], p[3], 1, 2, 3, 0);
    const Sign got = orient3d_perturbed_query(p[0], p[1], p[2], p[3]);
    // The face seen from the other tetrahedron (reversed) puts q on the other side.
    const Sign reversed = orient3d_perturbed_query(p[0], p[2], p[1], p[3]);
    if (got != expected || got == Sign::zero || reversed != -got) disagreements.add(c, hex(p));
  }
  disagreements.expect_none(kCases);
}

}  // namespace
}  // namespace tetrapage::geometry
