#include "tetrapage/runtime/query/MeshWalk.h"

#include <cstdio>
#include <string>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/runtime/geometry/Predicates.h"

namespace tetrapage {
namespace {

using geometry::Point;
using geometry::Sign;
using geometry::kTetrahedronFaces;

// Symbolic ranks for Simulation of Simplicity. Within one walk the source, the target and the
// mesh vertices must all differ; the reference point, the start of a walked segment and the
// target differ from each other so that a segment walk can reuse the located start tet.
constexpr std::uint64_t kReferenceId = 0;
constexpr std::uint64_t kSegmentStartId = 1;
constexpr std::uint64_t kTargetId = 2;
constexpr std::uint64_t kFirstVertexId = 3;

std::string format_point(const Point& p) {
  char buffer[96];
  std::snprintf(buffer, sizeof buffer, "(%.17g, %.17g, %.17g)", p[0], p[1], p[2]);
  return buffer;
}

void check_arguments(const TetMesh& mesh, std::uint32_t start_tet, const Point& p,
                     const char* what) {
  if (mesh.tets.empty()) throw InputError("mesh walk: the mesh has no tet");
  if (start_tet >= mesh.tet_count())
    throw InputError("mesh walk: start tet " + std::to_string(start_tet) + " is out of range (" +
                     std::to_string(mesh.tet_count()) + " tets)");
  if (!geometry::is_finite(p))
    throw InputError(std::string("mesh walk: ") + what + " " + format_point(p) +
                     " is not finite");
}

// A tet holding the symbolically perturbed source strictly inside, and the reference point to
// start from.
struct StartPoint {
  std::uint32_t tet;
  Point point;
};

StartPoint start_point(const TetMesh& mesh, std::uint32_t start_tet) {
  if (auto point = walk_reference_point(mesh, start_tet)) return {start_tet, *point};
  // A sliver too thin for a double inside it: start from the nearest tet that has one.
  std::vector<bool> seen(mesh.tet_count(), false);
  std::vector<std::uint32_t> queue{start_tet};
  seen[start_tet] = true;
  for (std::size_t head = 0; head < queue.size(); ++head) {
    for (std::uint32_t next : mesh.neighbours[queue[head]]) {
      if (next == TetMesh::no_neighbour || seen[next]) continue;
      seen[next] = true;
      if (auto point = walk_reference_point(mesh, next)) return {next, *point};
      queue.push_back(next);
    }
  }
  throw Error("mesh walk: no tet reachable from tet " + std::to_string(start_tet) +
              " has a double-precision point strictly inside it");
}

struct WalkEnd {
  std::uint32_t last_tet;
  std::uint32_t steps;
  bool target_inside;  ///< else the segment left the mesh through a hull face of last_tet
};

// The straight walk from source (strictly inside tet under the perturbation) to target. The
// segment's line crosses triangle (f0, f1, f2) from the side of the tet's own vertex to the far
// side exactly when orient3d(source, target, x, y) is negative for the three edges (f0, f1),
// (f1, f2), (f2, f0) of the face as kTetrahedronFaces orders it; perturbed, these signs are
// never zero, so exactly one face other than the entry face qualifies.
template <class Visit>
WalkEnd walk(const TetMesh& mesh, std::uint32_t tet, const Point& source, std::uint64_t source_id,
             const Point& target, std::uint64_t target_id, Visit&& visit) {
  const std::uint64_t step_cap = std::uint64_t(mesh.tet_count()) + 1;
  int entry = -1;
  std::uint32_t steps = 0;
  for (;;) {
    const auto& corner_index = mesh.tets[tet];
    Point c[4];
    std::uint64_t id[4];
    for (int i = 0; i < 4; ++i) {
      c[i] = mesh.vertices[corner_index[i]];
      id[i] = kFirstVertexId + corner_index[i];
    }
    // Plücker-like edge signs, computed once per edge: sigma[i][j] = -sigma[j][i].
    int sigma[4][4];
    bool known[4][4] = {};
    auto edge_sign = [&](int i, int j) {
      if (!known[i][j]) {
        const Sign s = geometry::orient3d_sos(source, target, c[i], c[j], source_id, target_id,
                                              id[i], id[j]);
        sigma[i][j] = geometry::to_int(s);
        sigma[j][i] = -sigma[i][j];
        known[i][j] = known[j][i] = true;
      }
      return sigma[i][j];
    };
    if (entry >= 0) {
      // The line came in through the entry face: its edges have the inward sign.
      const auto& f = kTetrahedronFaces[entry];
      for (int e = 0; e < 3; ++e) {
        const int i = f[e], j = f[e == 2 ? 0 : e + 1];
        sigma[i][j] = 1;
        sigma[j][i] = -1;
        known[i][j] = known[j][i] = true;
      }
    }
    int exit = -1;
    for (int k = 0; k < 4 && exit < 0; ++k) {
      if (k == entry) continue;
      const auto& f = kTetrahedronFaces[k];
      if (edge_sign(f[0], f[1]) < 0 && edge_sign(f[1], f[2]) < 0 && edge_sign(f[2], f[0]) < 0)
        exit = k;
    }
    if (exit < 0)
      throw Error("mesh walk: the segment " + format_point(source) + " -> " +
                  format_point(target) + " leaves tet " + std::to_string(tet) +
                  " through no face (inverted tet or inconsistent neighbours)");
    const auto& f = kTetrahedronFaces[exit];
    if (geometry::orient3d_sos(c[f[0]], c[f[1]], c[f[2]], target, id[f[0]], id[f[1]], id[f[2]],
                               target_id) != Sign::negative)
      return {tet, steps, true};  // the target comes before the exit face
    const std::uint32_t next = mesh.neighbours[tet][exit];
    if (next == TetMesh::no_neighbour) return {tet, steps, false};
    entry = -1;
    for (int k = 0; k < 4; ++k)
      if (mesh.neighbours[next][k] == tet) entry = k;
    if (entry < 0)
      throw Error("mesh walk: tet " + std::to_string(next) + " does not list tet " +
                  std::to_string(tet) + " as its neighbour");
    if (++steps > step_cap)
      throw Error("mesh walk: the walk from " + format_point(source) + " to " +
                  format_point(target) + " exceeded " + std::to_string(step_cap) +
                  " steps (invalid mesh)");
    visit(next);
    tet = next;
  }
}

}  // namespace

std::optional<Point> walk_reference_point(const TetMesh& mesh, std::uint32_t tet) {
  if (tet >= mesh.tet_count())
    throw InputError("mesh walk: tet " + std::to_string(tet) + " is out of range (" +
                     std::to_string(mesh.tet_count()) + " tets)");
  const auto t = mesh.corners(tet);
  const Sign orientation = geometry::orient3d(t[0], t[1], t[2], t[3]);
  if (orientation == Sign::zero) return std::nullopt;
  auto strictly_inside = [&](const Point& p) {
    for (Sign s : geometry::face_signs(p, t))
      if (s != orientation) return false;
    return true;
  };
  // The centroid, then points pulled towards each vertex in turn: for a sliver, rounding can
  // push the centroid out while a point nearer a vertex stays in.
  Point centroid;
  for (int k = 0; k < 3; ++k) centroid[k] = ((t[0][k] + t[1][k]) + (t[2][k] + t[3][k])) * 0.25;
  if (strictly_inside(centroid)) return centroid;
  for (int v = 0; v < 4; ++v) {
    Point p;
    for (int k = 0; k < 3; ++k) p[k] = 0.5 * centroid[k] + 0.5 * t[v][k];
    if (strictly_inside(p)) return p;
  }
  return std::nullopt;
}

WalkResult locate_point(const TetMesh& mesh, std::uint32_t start_tet, const Point& p) {
  check_arguments(mesh, start_tet, p, "point");
  // Most calls locate a point that has stayed strictly inside the last tet (a flying object's
  // steps): the walk, from a reference point, would end there too. Points on its boundary
  // take the walk, whose perturbation decides their tet.
  const auto here = geometry::locate_in_tetrahedron(p, mesh.corners(start_tet));
  if (here.position == geometry::TetrahedronPosition::inside) {
    WalkResult result;
    result.tet = start_tet;
    result.location = here;
    return result;
  }
  const StartPoint start = start_point(mesh, start_tet);
  const WalkEnd end =
      walk(mesh, start.tet, start.point, kReferenceId, p, kTargetId, [](std::uint32_t) {});
  WalkResult result;
  result.tets_crossed = end.steps;
  const auto location = geometry::locate_in_tetrahedron(p, mesh.corners(end.last_tet));
  if (end.target_inside && location.position == geometry::TetrahedronPosition::outside)
    throw Error("mesh walk: tet " + std::to_string(end.last_tet) + " holds the perturbed point " +
                format_point(p) + " but not the point itself (invalid mesh)");
  // Left through the hull: a point on the hull itself is still held by the last tet.
  if (location.position != geometry::TetrahedronPosition::outside) {
    result.tet = end.last_tet;
    result.location = location;
  }
  return result;
}

SegmentWalk walk_segment(const TetMesh& mesh, std::uint32_t start_tet, const Point& a,
                         const Point& b) {
  check_arguments(mesh, start_tet, a, "segment start");
  check_arguments(mesh, start_tet, b, "segment end");
  SegmentWalk out;
  const StartPoint start = start_point(mesh, start_tet);
  const WalkEnd at_a =
      walk(mesh, start.tet, start.point, kReferenceId, a, kSegmentStartId, [](std::uint32_t) {});
  out.tets_crossed_to_locate_a = at_a.steps;
  if (!at_a.target_inside) return out;
  // a, perturbed with the same rank, is strictly inside this tet: the source of the next walk.
  out.tets.push_back(at_a.last_tet);
  const WalkEnd at_b = walk(mesh, at_a.last_tet, a, kSegmentStartId, b, kTargetId,
                            [&](std::uint32_t tet) { out.tets.push_back(tet); });
  out.complete = at_b.target_inside ||
                 geometry::locate_in_tetrahedron(b, mesh.corners(at_b.last_tet)).position !=
                     geometry::TetrahedronPosition::outside;
  return out;
}

}  // namespace tetrapage
