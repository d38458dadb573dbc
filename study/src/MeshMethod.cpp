#include "tetrapage/study/MeshMethod.h"

#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_cell_base_with_info_3.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "Obstacles.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/index/TetMesh.h"
#include "tetrapage/runtime/geometry/PointTetrahedron.h"
#include "tetrapage/runtime/geometry/Predicates.h"
#include "tetrapage/runtime/geometry/SegmentTriangle.h"
#include "tetrapage/runtime/geometry/TriangleTetrahedron.h"
#include "tetrapage/runtime/query/MeshWalk.h"

namespace tetrapage::study {
namespace {

using geometry::Box;
using geometry::Point;
using geometry::Triangle;

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
// Vertex info: the index of the site it was inserted as (obstacle vertex, box corner, grid
// point or Steiner point); cell info: its index while the triangulation is flattened.
using VertexBase = CGAL::Triangulation_vertex_base_with_info_3<std::uint32_t, Kernel>;
using CellBase = CGAL::Triangulation_cell_base_with_info_3<
    std::uint32_t, Kernel, CGAL::Delaunay_triangulation_cell_base_3<Kernel>>;
using DataStructure = CGAL::Triangulation_data_structure_3<VertexBase, CellBase>;
using Delaunay = CGAL::Delaunay_triangulation_3<Kernel, DataStructure>;

constexpr std::uint32_t kNone = TetMesh::no_neighbour;
constexpr int kTetEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

// The triangulation as arrays, with one tet around every vertex (where walks start).
struct FlatMesh {
  TetMesh mesh;
  std::vector<std::uint32_t> vertex_tet;  ///< by mesh vertex
  std::vector<std::uint32_t> site_vertex; ///< by site: its mesh vertex (kNone if merged away)
};

FlatMesh flatten(Delaunay& delaunay, std::size_t sites) {
  FlatMesh out;
  out.site_vertex.assign(sites, kNone);
  std::vector<Delaunay::Vertex_handle> by_site(sites);
  for (auto v = delaunay.finite_vertices_begin(); v != delaunay.finite_vertices_end(); ++v)
    by_site[v->info()] = v;
  for (std::size_t s = 0; s < sites; ++s) {
    if (by_site[s] == Delaunay::Vertex_handle()) continue;
    out.site_vertex[s] = static_cast<std::uint32_t>(out.mesh.vertices.size());
    const auto& p = by_site[s]->point();
    out.mesh.vertices.push_back({p.x(), p.y(), p.z()});
  }
  out.vertex_tet.assign(out.mesh.vertices.size(), kNone);
  for (auto c = delaunay.finite_cells_begin(); c != delaunay.finite_cells_end(); ++c) {
    const auto tet = static_cast<std::uint32_t>(out.mesh.tets.size());
    c->info() = tet;
    std::array<std::uint32_t, 4> corners;
    for (int i = 0; i < 4; ++i) {
      corners[i] = out.site_vertex[c->vertex(i)->info()];
      out.vertex_tet[corners[i]] = tet;
    }
    out.mesh.tets.push_back(corners);
  }
  out.mesh.neighbours.resize(out.mesh.tets.size());
  for (auto c = delaunay.finite_cells_begin(); c != delaunay.finite_cells_end(); ++c) {
    auto& n = out.mesh.neighbours[c->info()];
    for (int i = 0; i < 4; ++i) {
      const auto neighbour = c->neighbor(i);
      n[i] = delaunay.is_infinite(neighbour) ? kNone : neighbour->info();
    }
  }
  return out;
}

// Per-thread visit stamps over the tets, for the breadth-first searches.
struct Scratch {
  std::vector<std::uint32_t> stamps;
  std::uint32_t stamp = 0;
  std::vector<std::uint32_t> queue;

  void start(std::size_t tets) {
    if (stamps.size() != tets || ++stamp == 0) {
      stamps.assign(tets, 0);
      stamp = 1;
    }
    queue.clear();
  }
  bool visit(std::uint32_t tet) {
    if (stamps[tet] == stamp) return false;
    stamps[tet] = stamp;
    queue.push_back(tet);
    return true;
  }
};

// Breadth-first search from `start` over the tets whose boxes overlap `box` and that pass
// `reach(tet)`; calls visit(tet) for each one reached, and stops early when it returns true.
template <class Reach, class Visit>
void search_tets(const TetMesh& mesh, const std::vector<Box>& tet_boxes, std::uint32_t start, const Box& box,
                 Scratch& scratch, Reach&& reach, Visit&& visit) {
  scratch.start(mesh.tet_count());
  scratch.visit(start);
  for (std::size_t head = 0; head < scratch.queue.size(); ++head) {
    const std::uint32_t tet = scratch.queue[head];
    if (visit(tet)) return;
    for (std::uint32_t next : mesh.neighbours[tet]) {
      if (next == kNone || scratch.stamps[next] == scratch.stamp) continue;
      if (!geometry::boxes_overlap(tet_boxes[next], box) || !reach(next)) continue;
      scratch.visit(next);
    }
  }
}

std::vector<Box> tet_boxes_of(const TetMesh& mesh) {
  std::vector<Box> boxes(mesh.tet_count());
  for (std::size_t t = 0; t < mesh.tet_count(); ++t) boxes[t] = mesh.bounds(t);
  return boxes;
}

// Signed distance to the plane of a triangle, in double (unit normal).
struct ApproximatePlane {
  Point origin{};
  std::array<double, 3> normal{};

  explicit ApproximatePlane(const Triangle& t) : origin(t[0]) {
    const std::array<double, 3> u{t[1][0] - t[0][0], t[1][1] - t[0][1], t[1][2] - t[0][2]};
    const std::array<double, 3> v{t[2][0] - t[0][0], t[2][1] - t[0][1], t[2][2] - t[0][2]};
    normal = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    const double length = std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
    if (length > 0)
      for (auto& n : normal) n /= length;
  }
  double distance(const Point& p) const {
    return normal[0] * (p[0] - origin[0]) + normal[1] * (p[1] - origin[1]) + normal[2] * (p[2] - origin[2]);
  }
};

// The point where the segment p -> q meets the plane, from the signed distances dp, dq of
// opposite signs (rounded).
Point cut(const Point& p, const Point& q, double dp, double dq) {
  const double s = dp / (dp - dq);
  return {p[0] + s * (q[0] - p[0]), p[1] + s * (q[1] - p[1]), p[2] + s * (q[2] - p[2])};
}

// Does obstacle triangle t cross the interior of a tet? Only where the tet has vertices
// farther than `tolerance` from t's plane on both sides: Steiner points are rounded to double,
// so they lie near t (its plane, its edges), never on it, and without the slack each one would
// be "crossed" again by the mesh edges and faces that end at it. Witnesses (exact): a tet edge
// with its ends on both sides that pierces t (split it where it meets the plane), or an edge
// of t through the relative interior of a tet face that straddles the plane (split t's edge
// there); a witness whose point is within the tolerance of a tet vertex is such a rounding
// artefact (t's edge passing beside a Steiner point placed on it), not a crossing.
std::optional<Point> find_crossing(const TetMesh& mesh, std::uint32_t tet, const Triangle& t,
                                   const ApproximatePlane& plane, double tolerance) {
  const auto c = mesh.corners(tet);
  double d[4];
  int side[4];
  bool above = false, below = false;
  for (int i = 0; i < 4; ++i) {
    d[i] = plane.distance(c[i]);
    side[i] = d[i] > tolerance ? 1 : (d[i] < -tolerance ? -1 : 0);
    above |= side[i] > 0;
    below |= side[i] < 0;
  }
  if (!above || !below) return std::nullopt;
  auto usable = [&](const Point& p) {
    if (!geometry::is_finite(p)) return false;
    for (const auto& v : c)
      if (std::max({std::fabs(v[0] - p[0]), std::fabs(v[1] - p[1]), std::fabs(v[2] - p[2])}) <= tolerance)
        return false;
    return true;
  };
  for (const auto& e : kTetEdges) {
    if (side[e[0]] * side[e[1]] >= 0) continue;
    const Point p = cut(c[e[0]], c[e[1]], d[e[0]], d[e[1]]);
    if (usable(p) && geometry::segment_intersects_triangle({c[e[0]], c[e[1]]}, t)) return p;
  }
  for (int k = 0; k < 4; ++k) {
    const auto& f = geometry::kTetrahedronFaces[k];
    bool face_above = false, face_below = false;
    for (int i : f) {
      face_above |= side[i] > 0;
      face_below |= side[i] < 0;
    }
    if (!face_above || !face_below) continue;
    const Triangle face{c[f[0]], c[f[1]], c[f[2]]};
    for (int e = 0; e < 3; ++e) {
      const geometry::Segment edge{t[e], t[(e + 1) % 3]};
      const ApproximatePlane face_plane(face);
      const double da = face_plane.distance(edge[0]), db = face_plane.distance(edge[1]);
      if ((da > 0) == (db > 0) || da == 0 || db == 0) continue;  // no usable point
      const Point p = cut(edge[0], edge[1], da, db);
      if (!usable(p)) continue;
      const auto hit = geometry::classify_segment_triangle(edge, face);
      if (!hit.at_endpoint && (hit.contact == geometry::SegmentTriangleContact::interior ||
                               hit.contact == geometry::SegmentTriangleContact::edge))
        return p;
    }
  }
  return std::nullopt;
}

// Uniform in [0, 1) with 53 bits, the same on every platform (std:: distributions are not).
double uniform(std::mt19937_64& random) {
  return double(random() >> 11) * 0x1.0p-53;
}

class MeshMethod final : public StudyMethod {
 public:
  MeshMethod(std::span<const Triangle> input, const MeshMethodOptions& options)
      : obstacles_(input, "mesh method"), options_(options) {
    if (!(options.max_growth >= 1.0) || !std::isfinite(options.max_growth))
      throw InputError("mesh method: max_growth " + std::to_string(options.max_growth) +
                       " must be a finite factor >= 1");
    if (options.grid_points > 256)
      throw InputError("mesh method: grid_points " + std::to_string(options.grid_points) +
                       " is above 256 (16.7 million points)");
    const auto started = std::chrono::steady_clock::now();
    build();
    statistics_.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    // A figure of the mesh, not part of building it.
    statistics_.details["average_stabbing_number"] = stabbing_number();
  }

  std::string name() const override { return "mesh"; }

  std::string parameters() const override {
    return "Delaunay + Steiner points, max rounds " + std::to_string(options_.max_rounds) + ", grid " +
           std::to_string(options_.grid_points);
  }

  bool collides(const PlacedObject& object, StudyCounters& counters) override;

  StudyStatistics statistics() const override { return statistics_; }

 private:
  void build();
  // Steiner rounds on the triangulation; leaves the final, flattened mesh in mesh_.
  void conform(Delaunay& delaunay, std::vector<Point>& sites);
  void attach_triangles();
  double stabbing_number();

  Obstacles obstacles_;
  MeshMethodOptions options_;
  Box hull_;                                  ///< the enlarged box: the mesh's convex hull
  std::vector<std::uint32_t> corner_site_;    ///< obstacle corner 3t+k -> its site
  TetMesh mesh_;
  std::vector<std::uint32_t> vertex_tet_;
  std::vector<std::uint32_t> site_vertex_;
  std::vector<Box> tet_boxes_;
  std::vector<std::uint32_t> tet_offsets_;    ///< CSR: obstacle triangles meeting each tet
  std::vector<std::uint32_t> tet_triangles_;

  // Conformity figures.
  std::size_t original_vertices_ = 0;
  std::size_t bounding_vertices_ = 0;
  std::size_t steiner_points_ = 0;
  unsigned rounds_ = 0;
  std::size_t non_conforming_ = 0;
  std::size_t degenerate_ = 0;
  std::string stopped_;
  StudyStatistics statistics_;

  // Query state: the tet of the last located corner, and visit stamps.
  std::uint32_t current_tet_ = 0;
  Scratch query_tets_;
  std::vector<std::uint32_t> triangle_stamps_;
  std::uint32_t triangle_stamp_ = 0;
  std::vector<std::uint32_t> candidates_;
};

void MeshMethod::build() {
  // Sites: the obstacle vertices (deduplicated), then the enlarged box's corners and the grid.
  std::vector<Point> sites;
  sites.reserve(obstacles_.size() * 3);
  for (const auto& t : obstacles_.triangles) sites.insert(sites.end(), t.begin(), t.end());
  std::sort(sites.begin(), sites.end());
  sites.erase(std::unique(sites.begin(), sites.end()), sites.end());
  original_vertices_ = sites.size();
  corner_site_.resize(obstacles_.size() * 3);
  for (std::size_t t = 0; t < obstacles_.size(); ++t)
    for (int k = 0; k < 3; ++k)
      corner_site_[3 * t + k] = static_cast<std::uint32_t>(
          std::lower_bound(sites.begin(), sites.end(), obstacles_.triangles[t][k]) - sites.begin());

  const Box& bounds = obstacles_.bounds;
  const Point size = bounds.size();
  const double largest = std::max({size[0], size[1], size[2]});
  // 10 % on every side (a flat or point-like model still gets a box with volume).
  const double pad = largest > 0 ? 0.1 * largest : std::max(1.0, std::fabs(bounds.lo[0]) * 1e-3);
  hull_ = geometry::inflated(bounds, pad);
  for (int i = 0; i < 8; ++i)
    sites.push_back({(i & 1) ? hull_.hi[0] : hull_.lo[0], (i & 2) ? hull_.hi[1] : hull_.lo[1],
                     (i & 4) ? hull_.hi[2] : hull_.lo[2]});
  const unsigned n = options_.grid_points;
  for (unsigned i = 0; i < n; ++i)
    for (unsigned j = 0; j < n; ++j)
      for (unsigned k = 0; k < n; ++k) {
        const double f[3] = {(i + 0.5) / n, (j + 0.5) / n, (k + 0.5) / n};
        Point p;
        for (int a = 0; a < 3; ++a) p[a] = bounds.lo[a] + f[a] * size[a];
        sites.push_back(p);
      }
  bounding_vertices_ = sites.size() - original_vertices_;

  std::vector<std::pair<Kernel::Point_3, std::uint32_t>> points;
  points.reserve(sites.size());
  for (std::size_t s = 0; s < sites.size(); ++s)
    points.emplace_back(Kernel::Point_3(sites[s][0], sites[s][1], sites[s][2]), static_cast<std::uint32_t>(s));
  Delaunay delaunay(points.begin(), points.end());
  // Grid points may coincide with obstacle vertices: count the ones that stayed.
  bounding_vertices_ = delaunay.number_of_vertices() - original_vertices_;
  conform(delaunay, sites);
  attach_triangles();

  query_tets_.start(mesh_.tet_count());
  triangle_stamps_.assign(obstacles_.size(), 0);

  statistics_.obstacle_triangles = obstacles_.size();
  statistics_.stored_triangles = tet_triangles_.size();
  statistics_.height = 0;
  statistics_.bytes = obstacles_.bytes() + mesh_.vertices.capacity() * sizeof(Vec3) +
                      mesh_.tets.capacity() * sizeof(mesh_.tets[0]) +
                      mesh_.neighbours.capacity() * sizeof(mesh_.neighbours[0]) +
                      tet_boxes_.capacity() * sizeof(Box) +
                      (tet_offsets_.capacity() + tet_triangles_.capacity() + triangle_stamps_.capacity() +
                       query_tets_.stamps.capacity()) *
                          sizeof(std::uint32_t);
  const double vertices = double(mesh_.vertices.size());
  auto& details = statistics_.details;
  details["original_vertices"] = original_vertices_;
  details["bounding_vertices"] = bounding_vertices_;
  details["steiner_points"] = steiner_points_;
  details["growth_factor"] = double(original_vertices_ + steiner_points_) / double(original_vertices_);
  details["vertices"] = mesh_.vertices.size();
  details["tets"] = mesh_.tet_count();
  details["tets_per_vertex"] = double(mesh_.tet_count()) / vertices;
  details["rounds"] = rounds_;
  details["stopped"] = stopped_;
  details["non_conforming_triangles"] = non_conforming_;
  details["degenerate_triangles"] = degenerate_;
  details["conforming"] = non_conforming_ == 0;
}

void MeshMethod::conform(Delaunay& delaunay, std::vector<Point>& sites) {
  const Point size = hull_.size();
  const double tolerance = 1e-12 * std::sqrt(size[0] * size[0] + size[1] * size[1] + size[2] * size[2]);
  std::vector<std::uint8_t> degenerate(obstacles_.size());
  for (std::size_t t = 0; t < obstacles_.size(); ++t)
    degenerate[t] = geometry::is_degenerate(obstacles_.triangles[t]);
  degenerate_ = std::size_t(std::count(degenerate.begin(), degenerate.end(), 1));
  const std::size_t limit = std::size_t(options_.max_growth * double(original_vertices_));
  const std::size_t bounding = bounding_vertices_;

  tbb::enumerable_thread_specific<Scratch> scratches;
  // One Steiner point per crossed triangle per round.
  std::vector<std::optional<Point>> crossings(obstacles_.size());
  for (;;) {
    FlatMesh flat = flatten(delaunay, sites.size());
    mesh_ = std::move(flat.mesh);
    vertex_tet_ = std::move(flat.vertex_tet);
    site_vertex_ = std::move(flat.site_vertex);
    tet_boxes_ = tet_boxes_of(mesh_);

    // Degenerate triangles have no plane to conform to: they are kept as their edges, and
    // attached to the tets they meet like the others.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, obstacles_.size()), [&](const auto& range) {
      Scratch& scratch = scratches.local();
      for (std::size_t o = range.begin(); o != range.end(); ++o) {
        crossings[o].reset();
        if (degenerate[o]) continue;
        const Triangle& t = obstacles_.triangles[o];
        const ApproximatePlane plane(t);
        const std::uint32_t start = vertex_tet_[site_vertex_[corner_site_[3 * o]]];
        // A superset of the tets meeting t, connected and cheaper than the exact test: those
        // that its plane (with the slack) does not separate from t's box.
        search_tets(
            mesh_, tet_boxes_, start, geometry::box_of(t), scratch,
            [&](std::uint32_t tet) {
              bool above = false, below = false;
              for (auto v : mesh_.tets[tet]) {
                const double d = plane.distance(mesh_.vertices[v]);
                above |= d >= -tolerance;
                below |= d <= tolerance;
              }
              return above && below;
            },
            [&](std::uint32_t tet) {
              crossings[o] = find_crossing(mesh_, tet, t, plane, tolerance);
              return crossings[o].has_value();
            });
      }
    });
    std::vector<Point> steiner;
    for (const auto& c : crossings)
      if (c) steiner.push_back(*c);
    non_conforming_ = steiner.size();
    if (non_conforming_ == 0) {
      stopped_ = "conforming";
      break;
    }
    const std::size_t vertices = delaunay.number_of_vertices() - bounding;
    if (rounds_ >= options_.max_rounds) {
      stopped_ = "max_rounds";
      break;
    }
    if (vertices > limit) {
      stopped_ = "max_growth";
      break;
    }
    std::sort(steiner.begin(), steiner.end());
    steiner.erase(std::unique(steiner.begin(), steiner.end()), steiner.end());
    std::vector<std::pair<Kernel::Point_3, std::uint32_t>> points;
    for (const auto& p : steiner) {
      points.emplace_back(Kernel::Point_3(p[0], p[1], p[2]), static_cast<std::uint32_t>(sites.size()));
      sites.push_back(p);
    }
    const std::size_t before = delaunay.number_of_vertices();
    delaunay.insert(points.begin(), points.end());
    ++rounds_;
    if (delaunay.number_of_vertices() == before) {  // every point was a vertex already
      stopped_ = "no_progress";
      break;
    }
  }
  steiner_points_ = mesh_.vertices.size() - original_vertices_ - bounding;
}

void MeshMethod::attach_triangles() {
  std::vector<std::vector<std::uint32_t>> tets_of(obstacles_.size());
  tbb::enumerable_thread_specific<Scratch> scratches;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, obstacles_.size()), [&](const auto& range) {
    Scratch& scratch = scratches.local();
    for (std::size_t o = range.begin(); o != range.end(); ++o) {
      // Every tet whose closed solid meets the triangle, from a tet around one of its corners:
      // the tets meeting a connected set are connected through shared faces.
      const Triangle& t = obstacles_.triangles[o];
      const std::uint32_t start = vertex_tet_[site_vertex_[corner_site_[3 * o]]];
      search_tets(
          mesh_, tet_boxes_, start, geometry::box_of(t), scratch,
          [&](std::uint32_t tet) { return geometry::triangle_intersects_tetrahedron(t, mesh_.corners(tet)); },
          [](std::uint32_t) { return false; });
      tets_of[o] = scratch.queue;
    }
  });
  tet_offsets_.assign(mesh_.tet_count() + 1, 0);
  for (const auto& tets : tets_of)
    for (auto tet : tets) ++tet_offsets_[tet + 1];
  for (std::size_t t = 0; t < mesh_.tet_count(); ++t) tet_offsets_[t + 1] += tet_offsets_[t];
  tet_triangles_.resize(tet_offsets_.back());
  std::vector<std::uint32_t> fill(tet_offsets_.begin(), tet_offsets_.end() - 1);
  for (std::size_t o = 0; o < obstacles_.size(); ++o)
    for (auto tet : tets_of[o]) tet_triangles_[fill[tet]++] = static_cast<std::uint32_t>(o);
}

// The study's average line stabbing number (section 4.2.1): tets met per unit length by
// segments between uniform points of the obstacles' box, averaged over 1000 segments.
double MeshMethod::stabbing_number() {
  std::mt19937_64 random(1);
  const Box& box = obstacles_.bounds;
  auto draw = [&] {
    Point p;
    for (int a = 0; a < 3; ++a) p[a] = box.lo[a] + uniform(random) * (box.hi[a] - box.lo[a]);
    return p;
  };
  double sum = 0;
  std::size_t counted = 0;
  std::uint32_t start = 0;
  for (int s = 0; s < 1000; ++s) {
    const Point a = draw(), b = draw();
    const double length = std::sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) +
                                    (b[2] - a[2]) * (b[2] - a[2]));
    if (!(length > 0)) continue;  // a flat model's box: no segment has a length
    const SegmentWalk walk = walk_segment(mesh_, start, a, b);
    if (walk.tets.empty()) continue;
    start = walk.tets.back();
    sum += double(walk.tets.size()) / length;
    ++counted;
  }
  return counted ? sum / double(counted) : 0.0;
}

bool MeshMethod::collides(const PlacedObject& object, StudyCounters& counters) {
  ++counters.queries;
  const Box& box = object.box();
  // Every obstacle lies inside the hull: a box beside it meets nothing.
  if (!geometry::boxes_overlap(box, hull_)) return false;
  // Locate the box's low corner, clamped onto the hull: still a point of the box (the box
  // meets the hull), so its tet meets the box.
  Point corner;
  for (int a = 0; a < 3; ++a) corner[a] = std::clamp(box.lo[a], hull_.lo[a], hull_.hi[a]);
  const WalkResult located = locate_point(mesh_, current_tet_, corner);
  if (located.tet == kNone)
    throw Error("mesh method: the walk lost the corner (" + std::to_string(corner[0]) + ", " +
                std::to_string(corner[1]) + ", " + std::to_string(corner[2]) + ") inside the hull");
  current_tet_ = located.tet;

  // Phase I: the tets whose boxes overlap BB(F), reached through shared faces (the tets that
  // really meet BB(F) are connected, and their boxes overlap it).
  Scratch& tets = query_tets_;
  tets.start(mesh_.tet_count());
  tets.visit(current_tet_);
  if (++triangle_stamp_ == 0) {
    std::fill(triangle_stamps_.begin(), triangle_stamps_.end(), 0);
    triangle_stamp_ = 1;
  }
  candidates_.clear();
  for (std::size_t head = 0; head < tets.queue.size(); ++head) {
    const std::uint32_t tet = tets.queue[head];
    for (std::uint32_t i = tet_offsets_[tet]; i < tet_offsets_[tet + 1]; ++i) {
      const std::uint32_t o = tet_triangles_[i];
      if (triangle_stamps_[o] == triangle_stamp_) continue;
      triangle_stamps_[o] = triangle_stamp_;
      if (geometry::boxes_overlap(obstacles_.boxes[o], box)) candidates_.push_back(o);
    }
    for (std::uint32_t next : mesh_.neighbours[tet])
      if (next != kNone && tets.stamps[next] != tets.stamp && geometry::boxes_overlap(tet_boxes_[next], box))
        tets.visit(next);
  }
  counters.tets_occupied += tets.queue.size();
  if (candidates_.empty()) return false;

  // Phase II: every object triangle against the obstacle triangles found.
  ++counters.full_checks;
  const auto triangles = object.triangles();
  const auto boxes = object.triangle_boxes();
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    for (std::uint32_t o : candidates_)
      if (obstacles_.meets(triangles[i], boxes[i], o, counters)) {
        ++counters.collisions;
        return true;
      }
  }
  return false;
}

}  // namespace

std::unique_ptr<StudyMethod> make_mesh_method(std::span<const geometry::Triangle> obstacles,
                                              const MeshMethodOptions& options) {
  return std::make_unique<MeshMethod>(obstacles, options);
}

}  // namespace tetrapage::study
