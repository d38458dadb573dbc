// Point location in a tetrahedron: the exact classification against CGAL's exact kernel, and
// the perturbed test on meshes whose tetrahedra share faces, edges and vertices: a point on a
// shared feature is accepted by exactly one tetrahedron, and walks always terminate.

#include "tetrapage/runtime/geometry/PointTetrahedron.h"

#include <map>

#include "GeometryTestSupport.h"

namespace tetrapage::geometry {
namespace {

using namespace testing;

// The oracle: CGAL's own point/segment/triangle/tetrahedron membership tests.
TetrahedronPosition epeck_position(const Point& p, const Tetrahedron& t) {
  const auto q = to_epeck(p);
  for (const auto& v : t)
    if (to_epeck(v) == q) return TetrahedronPosition::on_vertex;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j)
      if (Epeck::Segment_3(to_epeck(t[i]), to_epeck(t[j])).has_on(q))
        return TetrahedronPosition::on_edge;
  for (const auto& f : kTetrahedronFaces)
    if (Epeck::Triangle_3(to_epeck(t[f[0]]), to_epeck(t[f[1]]), to_epeck(t[f[2]])).has_on(q))
      return TetrahedronPosition::on_face;
  return to_epeck(t).has_on_bounded_side(q) ? TetrahedronPosition::inside
                                            : TetrahedronPosition::outside;
}

TEST(PointTetrahedron, LocateMatchesEpeck) {
  constexpr std::uint64_t kCases = 150000;
  Disagreements disagreements("locate_in_tetrahedron");
  std::uint64_t tested = 0;
  for (std::uint64_t c = 0; c < kCases; ++c) {
    Generator g(c);
    const ExactTransform transform = random_exact_transform(g);
    const std::int64_t range = c % 3 == 0 ? 3 : (std::int64_t(1) << 20);
    Tetrahedron t;
    for (auto& v : t) v = lattice_point(g, range);
    if (c % 5 == 0) t[3] = dyadic_combination(t[0], t[1], t[2], 1, 1, 2);  // flat: degenerate
    // A point on a face, an edge, a vertex, inside, in a face plane, or random.
    const int face = int(g.integer(0, 3));
    const auto& f = kTetrahedronFaces[face];
    const Triangle face_triangle{t[f[0]], t[f[1]], t[f[2]]};
    Point p;
    switch (c % 6) {
      case 0: p = dyadic_point_on(g, face_triangle, 0); break;
      case 1: p = dyadic_point_on(g, face_triangle, 1); break;
      case 2: p = dyadic_point_on(g, face_triangle, 2); break;
      case 3: p = dyadic_point_on(g, face_triangle, 3); break;
      case 4: {  // inside: the average of the four vertices, in quarters
        for (int k = 0; k < 3; ++k) p[k] = (t[0][k] + t[1][k] + t[2][k] + t[3][k]) / 4;
        break;
      }
      default: p = lattice_point(g, range);
    }
    const Tetrahedron moved = transform(t);
    Point q = transform(p);
    if (c % 7 == 0) q = nudge(g, q);
    const bool degenerate = CGAL::orientation(to_epeck(moved[0]), to_epeck(moved[1]),
                                              to_epeck(moved[2]), to_epeck(moved[3])) == CGAL::ZERO;
    const TetrahedronLocation got = locate_in_tetrahedron(q, moved);
    ++tested;
    if (degenerate) {
      if (got.position != TetrahedronPosition::degenerate_tetrahedron)
        disagreements.add(c, "degenerate not reported: " + hex(moved));
      continue;
    }
    const TetrahedronPosition expected = epeck_position(q, moved);
    // The reported feature must hold the point: check the vertex mask against the oracle too.
    bool feature_ok = true;
    if (got.position == TetrahedronPosition::on_vertex) {
      const int v = got.vertices == 1 ? 0 : got.vertices == 2 ? 1 : got.vertices == 4 ? 2 : 3;
      feature_ok = moved[v] == q;
    } else if (got.position == TetrahedronPosition::on_face) {
      const auto& g_face = kTetrahedronFaces[got.face()];
      feature_ok = Epeck::Triangle_3(to_epeck(moved[g_face[0]]), to_epeck(moved[g_face[1]]),
                                     to_epeck(moved[g_face[2]]))
                       .has_on(to_epeck(q));
    } else if (got.position == TetrahedronPosition::on_edge) {
      int ends[2], n = 0;
      for (int v = 0; v < 4; ++v)
        if (got.vertices & (1 << v)) ends[n++ & 1] = v;
      feature_ok = n == 2 && Epeck::Segment_3(to_epeck(moved[ends[0]]), to_epeck(moved[ends[1]]))
                                 .has_on(to_epeck(q));
    }
    if (got.position != expected || !feature_ok)
      disagreements.add(c, "point " + hex(q) + " tetrahedron " + hex(moved) + " expected " +
                               std::to_string(int(expected)) + " got " +
                               std::to_string(int(got.position)));
  }
  disagreements.expect_none(tested);
}

// A Kuhn (Freudenthal) triangulation of an n^3 grid of cubes: six tetrahedra per cube around
// its main diagonal, conforming across cubes, with heavy sharing of faces, edges and vertices.
struct TetMesh {
  std::vector<Point> lattice;  // the untransformed lattice positions
  std::vector<Point> vertices;
  std::vector<std::array<std::uint32_t, 4>> tetrahedra;
  std::vector<std::array<std::int64_t, 4>> neighbours;  // across face k, or -1

  Tetrahedron tetrahedron(std::size_t t) const {
    return {vertices[tetrahedra[t][0]], vertices[tetrahedra[t][1]], vertices[tetrahedra[t][2]],
            vertices[tetrahedra[t][3]]};
  }
};

// `shear`: an integer unimodular map applied before the transform (keeps exactness, breaks the
// Delaunay property); false keeps a similarity (the mesh stays Delaunay).
TetMesh kuhn_grid(int n, const ExactTransform& transform, const std::array<std::int64_t, 9>& shear) {
  TetMesh mesh;
  auto id = [n](int i, int j, int k) { return std::uint32_t((i * (n + 1) + j) * (n + 1) + k); };
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j)
      for (int k = 0; k <= n; ++k) {
        const Point p{double(i), double(j), double(k)};
        mesh.lattice.push_back(p);
        Point s;
        for (int r = 0; r < 3; ++r)
          s[r] = double(shear[3 * r]) * p[0] + double(shear[3 * r + 1]) * p[1] +
                 double(shear[3 * r + 2]) * p[2];
        mesh.vertices.push_back(transform(s));
      }
  const int permutations[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
        for (const auto& perm : permutations) {
          int c[3] = {i, j, k};
          std::array<std::uint32_t, 4> t;
          t[0] = id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[perm[s]];
            t[s + 1] = id(c[0], c[1], c[2]);
          }
          const Tetrahedron geometry{mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]],
                                     mesh.vertices[t[3]]};
          if (orient3d(geometry[0], geometry[1], geometry[2], geometry[3]) == Sign::negative)
            std::swap(t[2], t[3]);
          mesh.tetrahedra.push_back(t);
        }
  std::map<std::array<std::uint32_t, 3>, std::pair<std::size_t, int>> faces;
  mesh.neighbours.assign(mesh.tetrahedra.size(), {-1, -1, -1, -1});
  for (std::size_t t = 0; t < mesh.tetrahedra.size(); ++t)
    for (int f = 0; f < 4; ++f) {
      std::array<std::uint32_t, 3> key;
      for (int v = 0; v < 3; ++v) key[v] = mesh.tetrahedra[t][kTetrahedronFaces[f][v]];
      std::sort(key.begin(), key.end());
      const auto [it, inserted] = faces.emplace(key, std::make_pair(t, f));
      if (!inserted) {
        mesh.neighbours[t][f] = std::int64_t(it->second.first);
        mesh.neighbours[it->second.first][it->second.second] = std::int64_t(t);
      }
    }
  return mesh;
}

// A lattice-space point on a random feature of a random tetrahedron, strictly inside the grid.
Point point_on_shared_feature(Generator& g, const TetMesh& mesh, int n, int feature) {
  while (true) {
    const auto& t = mesh.tetrahedra[g.integer(0, std::int64_t(mesh.tetrahedra.size()) - 1)];
    const Point a = mesh.lattice[t[0]], b = mesh.lattice[t[1]], c = mesh.lattice[t[2]],
                d = mesh.lattice[t[3]];
    Point p;
    switch (feature) {
      case 0: p = a; break;                                                    // a vertex
      case 1: p = dyadic_combination(a, b, b, g.integer(1, 255), 0, 8); break;  // an edge
      case 2: p = dyadic_point_on(g, {a, b, c}, 0); break;                     // a face
      default: {                                                               // inside
        const Point on_face = dyadic_point_on(g, {a, b, c}, 0);
        p = dyadic_combination(on_face, d, d, g.integer(1, 255), 0, 8);
      }
    }
    bool interior = true;
    for (double x : p) interior = interior && x > 0 && x < n;
    if (interior) return p;
  }
}

Point apply(const ExactTransform& transform, const std::array<std::int64_t, 9>& shear, const Point& p) {
  Point s;
  for (int r = 0; r < 3; ++r)
    s[r] = double(shear[3 * r]) * p[0] + double(shear[3 * r + 1]) * p[1] +
           double(shear[3 * r + 2]) * p[2];
  return transform(s);
}

TEST(PointTetrahedron, PerturbedLocationAcceptsExactlyOneTetrahedronOfAMesh) {
  constexpr int kGrid = 3;
  constexpr int kMeshes = 24;
  constexpr int kPointsPerMesh = 1500;
  Disagreements disagreements("perturbed location in a Kuhn grid");
  std::uint64_t tested = 0;
  for (int m = 0; m < kMeshes; ++m) {
    Generator g{std::uint64_t(m)};
    const ExactTransform transform = random_exact_transform(g, 16);
    // Half of the meshes sheared by a unimodular integer matrix (exact, not Delaunay).
    std::array<std::int64_t, 9> shear{1, 0, 0, 0, 1, 0, 0, 0, 1};
    if (m % 2) shear = {1, g.integer(-2, 2), g.integer(-2, 2), 0, 1, g.integer(-2, 2), 0, 0, 1};
    const TetMesh mesh = kuhn_grid(kGrid, transform, shear);
    for (int i = 0; i < kPointsPerMesh; ++i) {
      const std::uint64_t seed = std::uint64_t(m) * 1000000 + std::uint64_t(i);
      Generator pg(seed);
      const Point p = apply(transform, shear, point_on_shared_feature(pg, mesh, kGrid, i % 4));
      int accepted = 0, closed = 0;
      for (std::size_t t = 0; t < mesh.tetrahedra.size(); ++t) {
        const Tetrahedron tet = mesh.tetrahedron(t);
        accepted += point_in_tetrahedron_perturbed(p, tet);
        closed += locate_in_tetrahedron(p, tet).position != TetrahedronPosition::outside;
      }
      ++tested;
      if (accepted != 1 || closed < 1)
        disagreements.add(seed, "mesh " + std::to_string(m) + " point " + hex(p) + " accepted by " +
                                    std::to_string(accepted) + " (closed: " +
                                    std::to_string(closed) + ")");
    }
  }
  disagreements.expect_none(tested);
}

TEST(PointTetrahedron, HandBuiltStarsAcceptExactlyOnce) {
  // Four tetrahedra around the edge (0,0,-1)-(0,0,1); eight around the vertex at the origin.
  const Point bottom{0, 0, -1}, top{0, 0, 1};
  const Point ring[4] = {{1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
  std::vector<Tetrahedron> edge_star, vertex_star;
  for (int i = 0; i < 4; ++i) {
    edge_star.push_back({bottom, top, ring[i], ring[(i + 1) % 4]});
    for (const Point& pole : {bottom, top})
      vertex_star.push_back({Point{0, 0, 0}, pole, ring[i], ring[(i + 1) % 4]});
  }
  Disagreements disagreements("stars");
  std::uint64_t tested = 0;
  for (std::uint64_t c = 0; c < 20000; ++c) {
    Generator g(c);
    const ExactTransform transform = random_exact_transform(g, 16);
    const bool edge = c % 2 == 0;
    const auto& star = edge ? edge_star : vertex_star;
    // On the shared edge/vertex, or on a face shared by two neighbours.
    Point p{0, 0, 0};
    if (edge && c % 4 == 0) p = {0, 0, std::ldexp(double(g.integer(-255, 255)), -8)};
    if (c % 4 == 1 || c % 4 == 3) {
      const int i = int(g.integer(0, 3));
      const Point& pole = edge ? top : (g.coin() ? top : bottom);
      p = dyadic_point_on(g, {edge ? bottom : Point{0, 0, 0}, pole, ring[i]}, 0);
    }
    const Point q = transform(p);
    int accepted = 0;
    for (const auto& t : star) accepted += point_in_tetrahedron_perturbed(q, transform(t));
    ++tested;
    if (accepted != 1) disagreements.add(c, hex(q) + " accepted " + std::to_string(accepted));
  }
  disagreements.expect_none(tested);
}

TEST(PointTetrahedron, VisibilityWalksTerminateInTheAcceptingTetrahedron) {
  constexpr int kGrid = 4;
  Disagreements disagreements("walks");
  std::uint64_t walks = 0;
  for (int m = 0; m < 8; ++m) {
    Generator g{std::uint64_t(100 + m)};
    const ExactTransform transform = random_exact_transform(g, 16);
    const std::array<std::int64_t, 9> identity{1, 0, 0, 0, 1, 0, 0, 0, 1};
    const TetMesh mesh = kuhn_grid(kGrid, transform, identity);  // Delaunay: walks terminate
    for (int i = 0; i < 2000; ++i) {
      const std::uint64_t seed = std::uint64_t(m) * 1000000 + std::uint64_t(i);
      Generator pg(seed);
      const Point target = apply(transform, identity, point_on_shared_feature(pg, mesh, kGrid, i % 4));
      std::size_t current = std::size_t(pg.integer(0, std::int64_t(mesh.tetrahedra.size()) - 1));
      std::size_t steps = 0;
      bool left_mesh = false;
      for (; steps < 4 * mesh.tetrahedra.size(); ++steps) {
        const int face = exit_face_perturbed(target, mesh.tetrahedron(current));
        if (face < 0) break;
        const std::int64_t next = mesh.neighbours[current][face];
        if (next < 0) {
          left_mesh = true;
          break;
        }
        current = std::size_t(next);
      }
      ++walks;
      if (left_mesh || steps == 4 * mesh.tetrahedra.size() ||
          !point_in_tetrahedron_perturbed(target, mesh.tetrahedron(current)))
        disagreements.add(seed, "walk to " + hex(target) + " stopped after " + std::to_string(steps) +
                                    " steps" + (left_mesh ? " outside the mesh" : ""));
    }
  }
  disagreements.expect_none(walks);
}

}  // namespace
}  // namespace tetrapage::geometry
