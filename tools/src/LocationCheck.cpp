#include "tetrapage/tools/LocationCheck.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/Progress.h"
#include "tetrapage/runtime/geometry/PointTetrahedron.h"
#include "tetrapage/runtime/geometry/Predicates.h"
#include "tetrapage/runtime/query/MeshWalk.h"
#include "tetrapage/tools/Random.h"

namespace tetrapage {
namespace {

using geometry::Point;
using geometry::TetrahedronPosition;

constexpr std::uint32_t kOutside = TetMesh::no_neighbour;

// On-face and on-edge points are dyadic combinations (i a + j b + k c) / 2^m of the corners,
// kept when computed without rounding: a face whose corners carry all 53 bits holds about one
// exact double point in its interior (the double points of its plane form a lattice whose cell
// is about as large as the face), so small denominators find most of the few there are.
constexpr int kFaceLevels = 5;  // m <= 5: 594 weight triples per face
constexpr int kEdgeLevels = 8;  // m <= 8: 255 weight pairs per edge
constexpr int kTetEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

// Knuth's TwoSum: x + y == sum + error exactly.
void two_sum(double x, double y, double& sum, double& error) {
  sum = x + y;
  const double y_part = sum - x;
  error = (x - (sum - y_part)) + (y - y_part);
}

// i a + j b + k c (one coordinate) as six doubles whose exact sum it is (fma gives each
// product's rounding error), distilled by repeated error-free summation (Rump's VecSum);
// true, with the sum, when every error vanished, i.e. the exact value is a double.
bool exact_combination(int i, double a, int j, double b, int k, double c, double& out) {
  // A product by zero or a power of two is exact (short of overflow): skip the fma, a library
  // call without -mfma.
  const auto product = [](int w, double x, double& value, double& error) {
    value = w * x;
    error = (w & (w - 1)) == 0 ? 0.0 : std::fma(double(w), x, -value);
  };
  std::array<double, 6> terms;
  product(i, a, terms[0], terms[1]);
  product(j, b, terms[2], terms[3]);
  product(k, c, terms[4], terms[5]);
  for (int pass = 0; pass < 2; ++pass) {  // more passes find next to nothing more
    for (std::size_t n = 1; n < terms.size(); ++n) two_sum(terms[n - 1], terms[n], terms[n], terms[n - 1]);
    bool exact = true;
    for (std::size_t n = 0; n + 1 < terms.size(); ++n) exact &= terms[n] == 0;
    if (exact) {
      out = terms.back();
      return true;
    }
  }
  return false;
}

// (i a + j b + k c) * scale, scale a power of two, when its exact value is a double (a cheap
// filter before the exact predicates confirm where the point lies).
std::optional<Point> combine(int i, int j, int k, double scale, const Point& a, const Point& b,
                             const Point& c) {
  Point p;
  for (int axis = 0; axis < 3; ++axis) {
    double sum;
    if (!exact_combination(i, a[axis], j, b[axis], k, c[axis], sum)) return std::nullopt;
    p[axis] = sum * scale;
    if (p[axis] / scale != sum) return std::nullopt;  // underflow
  }
  return p;
}

// Every exact dyadic point in the relative interior of each face (each face once).
std::vector<Point> exact_face_points(const TetMesh& mesh, std::uint64_t& tried) {
  std::vector<Point> out;
  for (std::uint32_t t = 0; t < mesh.tet_count(); ++t) {
    const auto c = mesh.corners(t);
    for (int face = 0; face < 4; ++face) {
      const std::uint32_t n = mesh.neighbours[t][face];
      if (n != kOutside && n < t) continue;
      const auto& f = geometry::kTetrahedronFaces[face];
      for (int m = 2; m <= kFaceLevels; ++m) {
        const int whole = 1 << m;
        const double scale = std::ldexp(1.0, -m);
        for (int i = 1; i < whole - 1; ++i)
          for (int j = 1; i + j < whole; ++j) {
            const int k = whole - i - j;
            if (i % 2 == 0 && j % 2 == 0 && k % 2 == 0) continue;  // found at level m - 1
            ++tried;
            const auto p = combine(i, j, k, scale, c[f[0]], c[f[1]], c[f[2]]);
            if (!p) continue;
            const auto location = geometry::locate_in_tetrahedron(*p, c);
            if (location.position == TetrahedronPosition::on_face && location.face() == face)
              out.push_back(*p);
          }
      }
    }
  }
  return out;
}

// Every exact dyadic point in the relative interior of each edge (each edge once).
std::vector<Point> exact_edge_points(const TetMesh& mesh, std::uint64_t& tried) {
  struct Edge {
    std::uint32_t u, v, tet;
    int i, j;
  };
  std::vector<Edge> edges;
  edges.reserve(6 * mesh.tet_count());
  for (std::uint32_t t = 0; t < mesh.tet_count(); ++t)
    for (const auto& e : kTetEdges) {
      const std::uint32_t a = mesh.tets[t][e[0]], b = mesh.tets[t][e[1]];
      edges.push_back({std::min(a, b), std::max(a, b), t, e[0], e[1]});
    }
  std::sort(edges.begin(), edges.end(),
            [](const Edge& x, const Edge& y) { return x.u != y.u ? x.u < y.u : x.v < y.v; });
  edges.erase(std::unique(edges.begin(), edges.end(),
                          [](const Edge& x, const Edge& y) { return x.u == y.u && x.v == y.v; }),
              edges.end());
  std::vector<Point> out;
  for (const Edge& e : edges) {
    const auto c = mesh.corners(e.tet);
    for (int m = 1; m <= kEdgeLevels; ++m) {
      const int whole = 1 << m;
      const double scale = std::ldexp(1.0, -m);
      for (int i = 1; i < whole; i += 2) {  // odd: even numerators were found at level m - 1
        ++tried;
        const auto p = combine(i, whole - i, 0, scale, c[e.i], c[e.j], c[e.i]);
        if (!p) continue;
        const auto location = geometry::locate_in_tetrahedron(*p, c);
        if (location.position == TetrahedronPosition::on_edge &&
            location.vertices == ((1u << e.i) | (1u << e.j)))
          out.push_back(*p);
      }
    }
  }
  return out;
}

std::string format_answer(const std::vector<std::uint32_t>& tets, bool outside) {
  std::string text;
  for (std::uint32_t t : tets) text += (text.empty() ? "tet " : ", tet ") + std::to_string(t);
  if (outside) text += text.empty() ? "outside" : ", outside";
  return text.empty() ? "nothing" : text;
}

enum class Outcome : std::uint8_t { same_tet, exact_tie, outside, disagreement };

struct PointResult {
  Outcome outcome = Outcome::same_tet;
  std::uint32_t faces_hit = 0;
  std::uint32_t resyncs = 0;
  bool ambiguous = false;
  std::optional<LocationDisagreement> disagreement;
};

// The mesh, its vertex stars, and the verdict rule of LocationCheck.h.
class Judge {
 public:
  Judge(const EmbreeMeshFaces& faces, const PointLocator& locator)
      : faces_(faces), mesh_(faces.mesh()), locator_(locator) {
    star_begin_.assign(mesh_.vertices.size() + 1, 0);
    for (const auto& tet : mesh_.tets)
      for (std::uint32_t v : tet) ++star_begin_[v + 1];
    for (std::size_t v = 0; v < mesh_.vertices.size(); ++v) star_begin_[v + 1] += star_begin_[v];
    star_.resize(star_begin_.back());
    std::vector<std::uint32_t> fill(star_begin_.begin(), star_begin_.end() - 1);
    for (std::uint32_t t = 0; t < mesh_.tet_count(); ++t)
      for (std::uint32_t v : mesh_.tets[t]) star_[fill[v]++] = t;
  }

  PointResult judge(const LocationPoint& point) const {
    if (point.embree_start >= mesh_.tet_count())
      throw InputError("location check: start tet " + std::to_string(point.embree_start) +
                       " is out of range (" + std::to_string(mesh_.tet_count()) + " tets)");
    const auto reference = walk_reference_point(mesh_, point.embree_start);
    if (!reference)
      throw InputError("location check: start tet " + std::to_string(point.embree_start) +
                       " has no point strictly inside it");
    const FaceTrace trace = faces_.trace(point.embree_start, *reference, point.point);
    const std::uint32_t located = locator_(point.point, point.locator_start);

    PointResult result;
    result.faces_hit = trace.faces_hit;
    result.resyncs = trace.resyncs;
    result.ambiguous = trace.end_tets.size() + (trace.outside ? 1 : 0) > 1;
    std::vector<std::uint32_t> around = trace.end_tets;
    for (std::uint32_t t : trace.exit_tets)
      if (std::find(around.begin(), around.end(), t) == around.end()) around.push_back(t);

    auto disagree = [&](std::string reason) {
      result.outcome = Outcome::disagreement;
      result.disagreement = LocationDisagreement{point.point, point.kind,       located,
                                                 trace.end_tets, trace.outside, std::move(reason)};
      return result;
    };
    if (located == kOutside) {
      if (proven_outside(point.point, around)) {
        // Embree may put a point within float error outside the hull inside it.
        result.outcome = trace.outside && trace.end_tets.empty() ? Outcome::outside : Outcome::exact_tie;
        return result;
      }
      return disagree("located outside, but no hull face around Embree's answer (" +
                      format_answer(trace.end_tets, trace.outside) +
                      ") has the point strictly beyond it");
    }
    if (located >= mesh_.tet_count())
      return disagree("located tet " + std::to_string(located) + " is not a tet of the mesh");
    if (geometry::locate_in_tetrahedron(point.point, mesh_.corners(located)).position ==
        TetrahedronPosition::outside)
      return disagree("tet " + std::to_string(located) +
                      " does not hold the point (exact predicate); Embree says " +
                      format_answer(trace.end_tets, trace.outside));
    if (!trace.outside && trace.end_tets.size() == 1 && trace.end_tets[0] == located) {
      result.outcome = Outcome::same_tet;
      return result;
    }
    for (std::uint32_t t : around)
      if (shares_vertex(t, located)) {
        result.outcome = Outcome::exact_tie;
        return result;
      }
    return disagree("tet " + std::to_string(located) +
                    " holds the point, but Embree's trace ends far from it (" +
                    format_answer(trace.end_tets, trace.outside) + ")");
  }

 private:
  bool shares_vertex(std::uint32_t a, std::uint32_t b) const {
    for (std::uint32_t u : mesh_.tets[a])
      for (std::uint32_t v : mesh_.tets[b])
        if (u == v) return true;
    return false;
  }

  // Exact: p strictly beyond the plane of a hull face of a tet sharing a vertex with one of
  // `around`. The mesh is convex, so that plane separates p from the whole mesh.
  bool proven_outside(const Point& p, const std::vector<std::uint32_t>& around) const {
    for (std::uint32_t t : around)
      for (std::uint32_t v : mesh_.tets[t])
        for (std::uint32_t i = star_begin_[v]; i < star_begin_[v + 1]; ++i) {
          const std::uint32_t s = star_[i];
          for (int k = 0; k < 4; ++k) {
            if (mesh_.neighbours[s][k] != kOutside) continue;
            const auto& f = geometry::kTetrahedronFaces[k];
            const auto& c = mesh_.tets[s];
            // orient3d(face, own vertex) > 0 for a positive tet: negative is the far side.
            if (geometry::orient3d(mesh_.vertices[c[f[0]]], mesh_.vertices[c[f[1]]],
                                   mesh_.vertices[c[f[2]]], p) == geometry::Sign::negative)
              return true;
          }
        }
    return false;
  }

  const EmbreeMeshFaces& faces_;
  const TetMesh& mesh_;
  const PointLocator& locator_;
  std::vector<std::uint32_t> star_begin_, star_;
};

}  // namespace

const char* to_string(LocationPointKind kind) {
  switch (kind) {
    case LocationPointKind::random: return "random";
    case LocationPointKind::on_face: return "on face";
    case LocationPointKind::on_edge: return "on edge";
    case LocationPointKind::on_vertex: return "on vertex";
  }
  return "unknown";
}

LocationPointSet make_location_points(const TetMesh& mesh, const LocationPointOptions& options) {
  if (mesh.tets.empty()) throw InputError("location points: the mesh has no tet");
  for (double share : {options.random_share, options.face_share, options.edge_share})
    if (!(share >= 0 && share <= 1))
      throw InputError("location points: share " + std::to_string(share) + " is not in [0, 1]");
  if (options.random_share + options.face_share + options.edge_share > 1 + 1e-12)
    throw InputError("location points: the random, face and edge shares sum above 1");
  if (!(options.outside_margin >= 0))
    throw InputError("location points: negative outside margin " +
                     std::to_string(options.outside_margin));
  std::vector<std::uint32_t> startable;
  for (std::uint32_t t = 0; t < mesh.tet_count(); ++t)
    if (walk_reference_point(mesh, t)) startable.push_back(t);
  if (startable.empty())
    throw InputError("location points: no tet of the mesh has a point strictly inside it");

  Random random(options.seed);
  const auto share = [&](double s) { return std::uint64_t(std::llround(double(options.points) * s)); };
  std::array<std::uint64_t, kLocationPointKinds> wanted{};
  wanted[0] = std::min(options.points, share(options.random_share));
  wanted[1] = std::min(options.points - wanted[0], share(options.face_share));
  wanted[2] = std::min(options.points - wanted[0] - wanted[1], share(options.edge_share));
  wanted[3] = options.points - wanted[0] - wanted[1] - wanted[2];

  LocationPointSet set;
  set.points.reserve(options.points);
  auto add = [&](const Point& p, LocationPointKind kind) {
    LocationPoint point;
    point.point = p;
    point.kind = kind;
    point.embree_start = startable[random.below(startable.size())];
    point.locator_start = startable[random.below(startable.size())];
    set.points.push_back(point);
    ++set.count[std::size_t(kind)];
  };

  BoundingBox box;
  for (const auto& v : mesh.vertices) box.extend(v);
  const Vec3 size = box.size();
  for (std::uint64_t i = 0; i < wanted[0]; ++i) {
    Point p;
    for (int k = 0; k < 3; ++k) {
      const double grow = options.outside_margin * size[k];
      p[k] = random.uniform(box.lo[k] - grow, box.hi[k] + grow);
    }
    add(p, LocationPointKind::random);
    ++set.attempts[0];
  }
  // Exact points on faces and edges are few (see kFaceLevels): draw from all of them, so
  // that they repeat (with other start tets) when more are wanted than there are.
  const std::vector<Point> face_points = exact_face_points(mesh, set.attempts[1]);
  const std::vector<Point> edge_points = exact_edge_points(mesh, set.attempts[2]);
  if (!face_points.empty())
    for (std::uint64_t i = 0; i < wanted[1]; ++i)
      add(face_points[random.below(face_points.size())], LocationPointKind::on_face);
  if (!edge_points.empty())
    for (std::uint64_t i = 0; i < wanted[2]; ++i)
      add(edge_points[random.below(edge_points.size())], LocationPointKind::on_edge);
  for (std::uint64_t i = 0; i < wanted[3]; ++i) {
    ++set.attempts[3];
    const std::uint32_t t = std::uint32_t(random.below(mesh.tet_count()));
    add(mesh.vertices[mesh.tets[t][random.below(4)]], LocationPointKind::on_vertex);
  }
  std::array<std::vector<Point>, kLocationPointKinds> by_kind;
  for (const LocationPoint& p : set.points) by_kind[std::size_t(p.kind)].push_back(p.point);
  for (std::size_t k = 0; k < kLocationPointKinds; ++k) {
    std::sort(by_kind[k].begin(), by_kind[k].end());
    set.distinct[k] = std::uint64_t(std::unique(by_kind[k].begin(), by_kind[k].end()) - by_kind[k].begin());
  }
  return set;
}

PointLocator runtime_locator(const TetMesh& mesh) {
  return [&mesh](const Point& p, std::uint32_t start_tet) {
    return locate_point(mesh, start_tet, p).tet;
  };
}

LocationCheckSummary check_locations(const EmbreeMeshFaces& faces,
                                     std::span<const LocationPoint> points,
                                     const PointLocator& locator,
                                     const LocationCheckOptions& options) {
  const auto started = std::chrono::steady_clock::now();
  const Judge judge(faces, locator);
  LocationCheckSummary summary;
  summary.points = points.size();
  Progress progress("checking point location", points.size(), options.progress);
  tbb::task_arena arena(options.threads > 0 ? int(options.threads) : tbb::task_arena::automatic);
  constexpr std::size_t kBlock = 1 << 14;
  std::vector<PointResult> results;
  for (std::size_t begin = 0; begin < points.size(); begin += kBlock) {
    const std::size_t end = std::min(points.size(), begin + kBlock);
    results.assign(end - begin, PointResult{});
    arena.execute([&] {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(begin, end, 64),
                        [&](const tbb::blocked_range<std::size_t>& range) {
                          for (std::size_t i = range.begin(); i < range.end(); ++i)
                            results[i - begin] = judge.judge(points[i]);
                        });
    });
    // Reduced in point order, so the summary does not depend on the threads.
    for (std::size_t i = begin; i < end; ++i) {
      PointResult& r = results[i - begin];
      LocationOutcomes& kind = summary.by_kind[std::size_t(points[i].kind)];
      ++kind.points;
      summary.faces_hit += r.faces_hit;
      kind.resynced_traces += r.resyncs > 0 ? 1 : 0;
      kind.ambiguous_ends += r.ambiguous ? 1 : 0;
      summary.resynced_traces += r.resyncs > 0 ? 1 : 0;
      summary.ambiguous_ends += r.ambiguous ? 1 : 0;
      switch (r.outcome) {
        case Outcome::same_tet: ++kind.same_tet; break;
        case Outcome::exact_tie: ++kind.exact_ties; break;
        case Outcome::outside: ++kind.outside; break;
        case Outcome::disagreement:
          ++kind.disagreements;
          ++summary.disagreements;
          if (summary.listed.size() < options.max_listed)
            summary.listed.push_back(std::move(*r.disagreement));
          break;
      }
    }
    progress.advance(end - begin);
  }
  progress.finish();
  summary.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return summary;
}

}  // namespace tetrapage
