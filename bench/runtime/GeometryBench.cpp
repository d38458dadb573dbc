// Micro benchmarks of the geometry kernel: tests per second of each primitive in each accuracy
// mode, next to CGAL on the same inputs (the exact-construction kernel Epeck, and the
// filtered-predicate kernel Epick), with the disagreement rates of the epsilon modes against
// the exact answer printed as counters (false_negatives, false_positives: fractions of the
// inputs).
//
// Inputs (4096 of each, fixed seeds):
//  random        independent random triangles in a unit cube (mostly clear answers)
//  near_contact  a vertex or an edge point of b at a signed distance 10^U(-12,-3) (relative to
//                the triangle size) from a point of a: half touch through, half miss
//  touching      exact contacts (a vertex on a, built with dyadic coordinates): every sign is
//                zero, the worst case for exact filters

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <benchmark/benchmark.h>

#include <cmath>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "tetrapage/runtime/geometry/Accuracy.h"
#include "tetrapage/runtime/geometry/EpsilonTests.h"
#include "tetrapage/runtime/geometry/ObjectBVH.h"
#include "tetrapage/runtime/geometry/PointTetrahedron.h"
#include "tetrapage/runtime/geometry/Predicates.h"
#include "tetrapage/runtime/geometry/SegmentTriangle.h"
#include "tetrapage/runtime/geometry/TriangleBox.h"
#include "tetrapage/runtime/geometry/TriangleContact.h"
#include "tetrapage/runtime/geometry/TriangleDistance.h"
#include "tetrapage/runtime/geometry/TriangleTetrahedron.h"
#include "tetrapage/runtime/geometry/TriangleTriangle.h"

namespace {

using namespace tetrapage;
using namespace tetrapage::geometry;
using Epeck = CGAL::Exact_predicates_exact_constructions_kernel;
using Epick = CGAL::Exact_predicates_inexact_constructions_kernel;

constexpr std::size_t kInputs = 4096;  // a power of two

class Generator {
 public:
  explicit Generator(std::uint64_t seed) : engine_(seed) {}
  double uniform() { return double(engine_() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  bool coin() { return engine_() & 1; }
  Point point(double lo, double hi) { return {uniform(lo, hi), uniform(lo, hi), uniform(lo, hi)}; }

 private:
  std::mt19937_64 engine_;
};

Point add(const Point& a, const Point& b, double s = 1) {
  return {a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]};
}
Point sub(const Point& a, const Point& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Point unit_normal(const Triangle& t) {
  const Point u = sub(t[1], t[0]), v = sub(t[2], t[0]);
  Point n{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  const double l = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  return {n[0] / l, n[1] / l, n[2] / l};
}
// A point of t with random barycentric coordinates; on an edge when `edge`.
Point point_on(Generator& g, const Triangle& t, bool edge) {
  double b1 = g.uniform(), b2 = g.uniform();
  if (b1 + b2 > 1) b1 = 1 - b1, b2 = 1 - b2;
  if (edge) b2 = 1 - b1;
  return add(add(t[0], sub(t[1], t[0]), b1), sub(t[2], t[0]), b2);
}

struct Pair {
  Triangle a, b;
};

std::vector<Pair> random_pairs() {
  Generator g(1);
  std::vector<Pair> pairs(kInputs);
  for (auto& p : pairs) {
    const Point ca = g.point(0, 1), cb = g.point(0, 1);
    for (auto& v : p.a) v = add(ca, g.point(-0.3, 0.3));
    for (auto& v : p.b) v = add(cb, g.point(-0.3, 0.3));
  }
  return pairs;
}

std::vector<Pair> near_contact_pairs() {
  Generator g(2);
  std::vector<Pair> pairs(kInputs);
  for (auto& p : pairs) {
    for (auto& v : p.a) v = g.point(-1, 1);
    const Point n = unit_normal(p.a);
    const double side = g.coin() ? 1 : -1;
    const double delta = std::pow(10.0, g.uniform(-12, -3)) * (g.coin() ? 1 : -1);
    // b's apex sits delta beyond a point X of a (interior or edge); its base lies on one side.
    const Point x = point_on(g, p.a, g.coin());
    p.b[0] = add(x, n, side * delta);
    for (int i = 1; i < 3; ++i) {
      Point d = g.point(-1, 1);
      const double along = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
      d = add(d, n, side * (std::fabs(along) + 0.2) - along);  // strictly on the `side` half
      p.b[i] = add(x, d);
    }
  }
  return pairs;
}

std::vector<Pair> touching_pairs() {
  Generator g(3);
  std::vector<Pair> pairs(kInputs);
  auto lattice = [&] {
    return Point{std::floor(g.uniform(-64, 64)), std::floor(g.uniform(-64, 64)), std::floor(g.uniform(-64, 64))};
  };
  for (auto& p : pairs) {
    p.a = {lattice(), lattice(), lattice()};
    const double i = std::floor(g.uniform(1, 100)), j = std::floor(g.uniform(1, 256 - i));
    p.b[0] = add(add(p.a[0], sub(p.a[1], p.a[0]), i / 256), sub(p.a[2], p.a[0]), j / 256);
    p.b[1] = lattice();
    p.b[2] = lattice();
  }
  return pairs;
}

const std::vector<Pair>& pairs(const std::string& name) {
  static const std::vector<Pair> random = random_pairs();
  static const std::vector<Pair> near = near_contact_pairs();
  static const std::vector<Pair> touching = touching_pairs();
  return name == "random" ? random : (name == "near_contact" ? near : touching);
}

template <class Kernel>
typename Kernel::Triangle_3 to_cgal(const Triangle& t) {
  using P = typename Kernel::Point_3;
  return {P(t[0][0], t[0][1], t[0][2]), P(t[1][0], t[1][1], t[1][2]), P(t[2][0], t[2][1], t[2][2])};
}

// Runs `test` over the inputs; when `exact_answer` is given, reports the disagreement rates.
template <class Input, class Test>
void run(benchmark::State& state, const std::vector<Input>& inputs, Test test,
         const std::function<bool(const Input&)>& exact_answer = nullptr) {
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(test(inputs[i]));
    i = (i + 1) & (kInputs - 1);
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()));
  if (exact_answer) {
    double false_negatives = 0, false_positives = 0;
    for (const auto& input : inputs) {
      const bool truth = exact_answer(input), got = test(input);
      false_negatives += truth && !got;
      false_positives += !truth && got;
    }
    state.counters["false_negatives"] = false_negatives / double(inputs.size());
    state.counters["false_positives"] = false_positives / double(inputs.size());
  }
}

void register_triangle_triangle() {
  for (const std::string set : {"random", "near_contact", "touching"}) {
    const auto& data = pairs(set);
    const std::function<bool(const Pair&)> exact = [](const Pair& p) {
      return triangles_intersect(p.a, p.b);
    };
    const std::string prefix = "triangle_triangle/" + set + "/";
    benchmark::RegisterBenchmark((prefix + "exact").c_str(), [&data](benchmark::State& s) {
      run(s, data, [](const Pair& p) { return triangles_intersect(p.a, p.b); });
    });
    benchmark::RegisterBenchmark((prefix + "exact_classified").c_str(), [&data](benchmark::State& s) {
      run(s, data, [](const Pair& p) { return classify_triangles(p.a, p.b) != TriangleContact::none; });
    });
    benchmark::RegisterBenchmark((prefix + "double_eps").c_str(), [&data, exact](benchmark::State& s) {
      run(s, data,
          [](const Pair& p) {
            return epsilon::triangles_intersect<double>(p.a, p.b, epsilon::kDefaultDoubleEpsilon);
          },
          exact);
    });
    benchmark::RegisterBenchmark((prefix + "float_eps").c_str(), [&data, exact](benchmark::State& s) {
      run(s, data,
          [](const Pair& p) {
            return epsilon::triangles_intersect<float>(p.a, p.b, epsilon::kDefaultFloatEpsilon);
          },
          exact);
    });
    benchmark::RegisterBenchmark((prefix + "clearance_1e-6").c_str(), [&data, exact](benchmark::State& s) {
      run(s, data, [](const Pair& p) { return within_distance(p.a, p.b, 1e-6); }, exact);
    });
    benchmark::RegisterBenchmark((prefix + "cgal_epick_do_intersect").c_str(), [&data](benchmark::State& s) {
      std::vector<std::pair<Epick::Triangle_3, Epick::Triangle_3>> converted;
      for (const auto& p : data) converted.emplace_back(to_cgal<Epick>(p.a), to_cgal<Epick>(p.b));
      run(s, converted, [](const auto& p) { return CGAL::do_intersect(p.first, p.second); });
    });
    benchmark::RegisterBenchmark((prefix + "cgal_epeck_do_intersect").c_str(), [&data](benchmark::State& s) {
      std::vector<std::pair<Epeck::Triangle_3, Epeck::Triangle_3>> converted;
      for (const auto& p : data) converted.emplace_back(to_cgal<Epeck>(p.a), to_cgal<Epeck>(p.b));
      run(s, converted, [](const auto& p) { return CGAL::do_intersect(p.first, p.second); });
    });
  }
}

struct SegmentCase {
  Segment s;
  Triangle t;
};

void register_segment_triangle() {
  // b's apex edge (b0, b1) of the near-contact pairs: it ends delta away from a.
  static std::vector<SegmentCase> near, random;
  for (const auto& p : pairs("near_contact")) near.push_back({{p.b[1], add(p.b[0], sub(p.b[0], p.b[1]), 1e-3)}, p.a});
  for (const auto& p : pairs("random")) random.push_back({{p.b[0], p.b[1]}, p.a});
  for (auto* set : {&random, &near}) {
    const std::string prefix = std::string("segment_triangle/") + (set == &near ? "near_contact/" : "random/");
    const auto& data = *set;
    const std::function<bool(const SegmentCase&)> exact = [](const SegmentCase& c) {
      return segment_intersects_triangle(c.s, c.t);
    };
    benchmark::RegisterBenchmark((prefix + "exact").c_str(), [&data](benchmark::State& s) {
      run(s, data, [](const SegmentCase& c) { return segment_intersects_triangle(c.s, c.t); });
    });
    benchmark::RegisterBenchmark((prefix + "double_eps").c_str(), [&data, exact](benchmark::State& s) {
      run(s, data,
          [](const SegmentCase& c) {
            return epsilon::segment_intersects_triangle<double>(c.s, c.t, epsilon::kDefaultDoubleEpsilon);
          },
          exact);
    });
    benchmark::RegisterBenchmark((prefix + "float_eps").c_str(), [&data, exact](benchmark::State& s) {
      run(s, data,
          [](const SegmentCase& c) {
            return epsilon::segment_intersects_triangle<float>(c.s, c.t, epsilon::kDefaultFloatEpsilon);
          },
          exact);
    });
    benchmark::RegisterBenchmark((prefix + "cgal_epeck_do_intersect").c_str(), [&data](benchmark::State& s) {
      std::vector<std::pair<Epeck::Segment_3, Epeck::Triangle_3>> converted;
      for (const auto& c : data)
        converted.emplace_back(Epeck::Segment_3(Epeck::Point_3(c.s[0][0], c.s[0][1], c.s[0][2]),
                                                Epeck::Point_3(c.s[1][0], c.s[1][1], c.s[1][2])),
                               to_cgal<Epeck>(c.t));
      run(s, converted, [](const auto& c) { return CGAL::do_intersect(c.first, c.second); });
    });
  }
}

struct BoxCase {
  Triangle t;
  Box box;
};

void register_triangle_box() {
  // Boxes around a's vertex 0 of the pairs, triangles b: near contact and random.
  static std::vector<BoxCase> near, random;
  for (const auto& p : pairs("near_contact")) {
    Box box;
    box.lo = box.hi = p.b[0];
    box.extend(add(p.b[0], sub(p.b[1], p.b[0]), 0.3));  // a corner at b's apex: near a
    near.push_back({p.a, box});
  }
  for (const auto& p : pairs("random")) random.push_back({p.a, box_of(p.b)});
  for (auto* set : {&random, &near}) {
    const std::string prefix = std::string("triangle_box/") + (set == &near ? "near_contact/" : "random/");
    const auto& data = *set;
    const std::function<bool(const BoxCase&)> exact = [](const BoxCase& c) {
      return triangle_intersects_box(c.t, c.box);
    };
    benchmark::RegisterBenchmark((prefix + "exact").c_str(), [&data](benchmark::State& s) {
      run(s, data, [](const BoxCase& c) { return triangle_intersects_box(c.t, c.box); });
    });
    benchmark::RegisterBenchmark((prefix + "double_eps").c_str(), [&data, exact](benchmark::State& s) {
      run(s, data,
          [](const BoxCase& c) {
            return epsilon::triangle_intersects_box<double>(c.t, c.box, epsilon::kDefaultDoubleEpsilon);
          },
          exact);
    });
    benchmark::RegisterBenchmark((prefix + "float_eps").c_str(), [&data, exact](benchmark::State& s) {
      run(s, data,
          [](const BoxCase& c) {
            return epsilon::triangle_intersects_box<float>(c.t, c.box, epsilon::kDefaultFloatEpsilon);
          },
          exact);
    });
    benchmark::RegisterBenchmark((prefix + "cgal_epeck_do_intersect").c_str(), [&data](benchmark::State& s) {
      std::vector<std::pair<Epeck::Triangle_3, CGAL::Bbox_3>> converted;
      for (const auto& c : data)
        converted.emplace_back(to_cgal<Epeck>(c.t), CGAL::Bbox_3(c.box.lo[0], c.box.lo[1], c.box.lo[2],
                                                                 c.box.hi[0], c.box.hi[1], c.box.hi[2]));
      run(s, converted, [](const auto& c) { return CGAL::do_intersect(c.first, c.second); });
    });
  }
  benchmark::RegisterBenchmark("box_box/random/exact", [](benchmark::State& s) {
    static std::vector<std::pair<Box, Box>> boxes;
    for (const auto& p : pairs("random")) boxes.emplace_back(box_of(p.a), box_of(p.b));
    run(s, boxes, [](const auto& b) { return boxes_overlap(b.first, b.second); });
  });
}

struct TetrahedronCase {
  Point p;
  Triangle t;
  Tetrahedron tetrahedron;
};

void register_tetrahedra() {
  // Tetrahedra: a plus b's apex; points and triangles near their faces.
  static std::vector<TetrahedronCase> near;
  Generator g(4);
  for (const auto& p : pairs("near_contact")) {
    const Tetrahedron k{p.a[0], p.a[1], p.a[2], add(p.b[1], p.b[2], 1.0)};
    near.push_back({p.b[0], p.b, k});
  }
  const std::function<bool(const TetrahedronCase&)> exact_point = [](const TetrahedronCase& c) {
    return locate_in_tetrahedron(c.p, c.tetrahedron).position != TetrahedronPosition::outside;
  };
  benchmark::RegisterBenchmark("point_tetrahedron/near_contact/exact", [](benchmark::State& s) {
    run(s, near, [](const TetrahedronCase& c) {
      return locate_in_tetrahedron(c.p, c.tetrahedron).position != TetrahedronPosition::outside;
    });
  });
  benchmark::RegisterBenchmark("point_tetrahedron/near_contact/exact_perturbed", [](benchmark::State& s) {
    run(s, near, [](const TetrahedronCase& c) { return point_in_tetrahedron_perturbed(c.p, c.tetrahedron); });
  });
  benchmark::RegisterBenchmark("point_tetrahedron/near_contact/double_eps", [exact_point](benchmark::State& s) {
    run(s, near,
        [](const TetrahedronCase& c) {
          return epsilon::point_in_tetrahedron<double>(c.p, c.tetrahedron, epsilon::kDefaultDoubleEpsilon);
        },
        exact_point);
  });
  benchmark::RegisterBenchmark("point_tetrahedron/near_contact/float_eps", [exact_point](benchmark::State& s) {
    run(s, near,
        [](const TetrahedronCase& c) {
          return epsilon::point_in_tetrahedron<float>(c.p, c.tetrahedron, epsilon::kDefaultFloatEpsilon);
        },
        exact_point);
  });
  benchmark::RegisterBenchmark("triangle_tetrahedron/near_contact/exact", [](benchmark::State& s) {
    run(s, near, [](const TetrahedronCase& c) { return triangle_intersects_tetrahedron(c.t, c.tetrahedron); });
  });
  benchmark::RegisterBenchmark("triangle_tetrahedron/near_contact/cgal_epeck_do_intersect", [](benchmark::State& s) {
    std::vector<std::pair<Epeck::Triangle_3, Epeck::Tetrahedron_3>> converted;
    for (const auto& c : near) {
      const auto f = to_cgal<Epeck>({c.tetrahedron[0], c.tetrahedron[1], c.tetrahedron[2]});
      converted.emplace_back(to_cgal<Epeck>(c.t),
                             Epeck::Tetrahedron_3(f[0], f[1], f[2],
                                                  Epeck::Point_3(c.tetrahedron[3][0], c.tetrahedron[3][1],
                                                                 c.tetrahedron[3][2])));
    }
    run(s, converted, [](const auto& c) { return CGAL::do_intersect(c.first, c.second); });
  });
}

void register_orientation() {
  static std::vector<std::array<Point, 4>> quads;
  for (const auto& p : pairs("near_contact")) quads.push_back({p.a[0], p.a[1], p.a[2], p.b[0]});
  benchmark::RegisterBenchmark("orient3d/near_contact/exact", [](benchmark::State& s) {
    run(s, quads, [](const auto& q) { return static_cast<int>(orient3d(q[0], q[1], q[2], q[3])); });
  });
  benchmark::RegisterBenchmark("orient3d/near_contact/cgal_epick", [](benchmark::State& s) {
    run(s, quads, [](const auto& q) { return static_cast<int>(orient3d_cgal(q[0], q[1], q[2], q[3])); });
  });
  benchmark::RegisterBenchmark("orient3d/near_contact/cgal_epeck", [](benchmark::State& s) {
    std::vector<std::array<Epeck::Point_3, 4>> converted;
    for (const auto& q : quads)
      converted.push_back({Epeck::Point_3(q[0][0], q[0][1], q[0][2]), Epeck::Point_3(q[1][0], q[1][1], q[1][2]),
                           Epeck::Point_3(q[2][0], q[2][1], q[2][2]), Epeck::Point_3(q[3][0], q[3][1], q[3][2])});
    run(s, converted, [](const auto& q) { return CGAL::orientation(q[0], q[1], q[2], q[3]); });
  });
  static std::vector<std::array<Point, 4>> touching;
  for (const auto& p : pairs("touching")) touching.push_back({p.a[0], p.a[1], p.a[2], p.b[0]});
  benchmark::RegisterBenchmark("orient3d/touching/exact", [](benchmark::State& s) {
    run(s, touching, [](const auto& q) { return static_cast<int>(orient3d(q[0], q[1], q[2], q[3])); });
  });
}

void register_distance() {
  for (const std::string set : {"random", "near_contact"}) {
    const auto& data = pairs(set);
    benchmark::RegisterBenchmark(("triangle_distance/" + set + "/double").c_str(), [&data](benchmark::State& s) {
      run(s, data, [](const Pair& p) { return triangle_distance(p.a, p.b).distance; });
    });
  }
}

// Contact geometry on pairs that meet: crossing pairs (random pairs kept when they intersect),
// exact touching contacts, and coplanar overlapping pairs (polygons); Epeck's constructed
// intersection next to it on the crossing pairs.
void register_contact() {
  static std::vector<Pair> crossing, coplanar;
  Generator g(6);
  while (crossing.size() < kInputs) {
    Pair p;
    const Point ca = g.point(0, 1), cb = add(ca, g.point(-0.2, 0.2));
    for (auto& v : p.a) v = add(ca, g.point(-0.3, 0.3));
    for (auto& v : p.b) v = add(cb, g.point(-0.3, 0.3));
    if (triangles_intersect(p.a, p.b)) crossing.push_back(p);
  }
  while (coplanar.size() < kInputs) {  // lattice triangles in the plane z = 3
    Pair p;
    for (auto* t : {&p.a, &p.b})
      for (auto& v : *t) v = {std::floor(g.uniform(-64, 64)), std::floor(g.uniform(-64, 64)), 3};
    if (triangles_intersect(p.a, p.b)) coplanar.push_back(p);
  }
  const std::vector<std::pair<std::string, const std::vector<Pair>*>> sets{
      {"crossing", &crossing}, {"touching", &pairs("touching")}, {"coplanar", &coplanar}};
  for (const auto& [name, data] : sets)
    benchmark::RegisterBenchmark(("triangle_contact/" + name + "/double").c_str(), [data](benchmark::State& s) {
      run(s, *data, [](const Pair& p) { return contact_geometry(p.a, p.b).count; });
    });
  benchmark::RegisterBenchmark("triangle_contact/crossing/cgal_epeck_intersection", [](benchmark::State& s) {
    std::vector<std::pair<Epeck::Triangle_3, Epeck::Triangle_3>> converted;
    for (const auto& p : crossing) converted.emplace_back(to_cgal<Epeck>(p.a), to_cgal<Epeck>(p.b));
    run(s, converted, [](const auto& c) {
      const auto result = CGAL::intersection(c.first, c.second);
      double x = 0;  // read the endpoints (their interval approximations)
      if (const auto* segment = result ? boost::get<Epeck::Segment_3>(&*result) : nullptr)
        x = CGAL::to_double(segment->source().x()) + CGAL::to_double(segment->target().x());
      return x;
    });
  });
}

// Phase II: an object of ~20k triangles, queried by small environment triangles around it.
void register_bvh() {
  static TriangleSoup object;
  const int rings = 100, segments = 100;
  for (int r = 0; r <= rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const double theta = M_PI * r / rings, phi = 2 * M_PI * s / segments;
      object.vertices.push_back({std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)});
    }
  for (int r = 0; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      auto id = [](int rr, int ss) { return std::uint32_t(rr * segments + ss % segments); };
      object.triangles.push_back({id(r, s), id(r + 1, s), id(r + 1, s + 1)});
      object.triangles.push_back({id(r, s), id(r + 1, s + 1), id(r, s + 1)});
    }
  static const ObjectBVH bvh(object);
  static std::vector<Triangle> queries;
  Generator g(5);
  for (std::size_t i = 0; i < kInputs; ++i) {
    // Small triangles (size ~0.03) within 0.05 of the sphere's surface.
    Point c = g.point(-1, 1);
    const double l = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    const double radius = 1 + g.uniform(-0.05, 0.05);
    c = {c[0] / l * radius, c[1] / l * radius, c[2] / l * radius};
    queries.push_back({add(c, g.point(-0.03, 0.03)), add(c, g.point(-0.03, 0.03)), add(c, g.point(-0.03, 0.03))});
  }
  for (const Accuracy accuracy : {Accuracy::exact(), Accuracy::double_eps(), Accuracy::float_eps(),
                                  Accuracy::within(0.001)}) {
    benchmark::RegisterBenchmark(("object_bvh_first_hit/20k_sphere/" + to_string(accuracy)).c_str(),
                                 [accuracy](benchmark::State& s) {
                                   ObjectBVH::QueryCounters counters;
                                   run(s, queries, [&](const Triangle& q) {
                                     return bvh.first_hit(q, accuracy, &counters).has_value();
                                   });
                                   s.counters["triangle_tests_per_query"] =
                                       double(counters.triangle_tests) / double(s.iterations());
                                   s.counters["nodes_per_query"] =
                                       double(counters.nodes_visited) / double(s.iterations());
                                 });
  }
  benchmark::RegisterBenchmark("object_bvh_first_hit/20k_sphere/brute_force_exact", [](benchmark::State& s) {
    run(s, queries, [](const Triangle& q) { return bvh.first_hit_brute_force(q).has_value(); });
  });
  benchmark::RegisterBenchmark("object_bvh_build/20k_sphere", [](benchmark::State& s) {
    for (auto _ : s) benchmark::DoNotOptimize(ObjectBVH(object).node_count());
    s.SetItemsProcessed(std::int64_t(s.iterations() * object.triangle_count()));
  });
}

}  // namespace

int main(int argc, char** argv) {
  register_orientation();
  register_triangle_triangle();
  register_segment_triangle();
  register_triangle_box();
  register_tetrahedra();
  register_distance();
  register_contact();
  register_bvh();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
