#include "tetrapage/preprocess/CoarseMesh.h"

#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_cell_base_with_info_3.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "tetrapage/formats/base/Error.h"

namespace tetrapage {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_3<std::uint32_t, Kernel>;
using CellBase =
    CGAL::Triangulation_cell_base_with_info_3<std::uint32_t, Kernel,
                                              CGAL::Delaunay_triangulation_cell_base_3<Kernel>>;
using DataStructure = CGAL::Triangulation_data_structure_3<VertexBase, CellBase>;
using Delaunay = CGAL::Delaunay_triangulation_3<Kernel, DataStructure>;

// Median split along the longest side of the centroids' own box; appends each leaf's sites.
void split(std::span<Vec3> points, std::size_t begin, std::size_t end, std::size_t leaf,
           const BoundingBox& bounds, std::vector<Vec3>& sites) {
  if (end - begin <= leaf) {
    append_leaf_sites(points.subspan(begin, end - begin), bounds, sites);
    return;
  }
  BoundingBox box;
  for (std::size_t i = begin; i < end; ++i) box.extend(points[i]);
  const Vec3 size = box.size();
  const int axis = size[0] >= size[1] && size[0] >= size[2] ? 0 : (size[1] >= size[2] ? 1 : 2);
  if (size[axis] == 0.0) {  // all centroids coincide: one site is all they need
    sites.push_back(points[begin]);
    return;
  }
  const std::size_t middle = begin + (end - begin) / 2;
  std::nth_element(points.begin() + long(begin), points.begin() + long(middle),
                   points.begin() + long(end),
                   [axis](const Vec3& a, const Vec3& b) { return a[axis] < b[axis]; });
  // The halves are disjoint ranges: large ones split on two threads (the sample holds up to
  // 2M centroids, 4M when this was a serial 0.4 s of the 10M preprocess), their sites appended
  // left then right as the serial recursion does.
  constexpr std::size_t kParallelPoints = std::size_t(1) << 16;
  if (end - begin < kParallelPoints) {
    split(points, begin, middle, leaf, bounds, sites);
    split(points, middle, end, leaf, bounds, sites);
    return;
  }
  std::vector<Vec3> right_sites;
  tbb::parallel_invoke([&] { split(points, begin, middle, leaf, bounds, sites); },
                       [&] { split(points, middle, end, leaf, bounds, right_sites); });
  sites.insert(sites.end(), right_sites.begin(), right_sites.end());
}

}  // namespace

void append_leaf_sites(std::span<const Vec3> leaf, const BoundingBox& bounds,
                       std::vector<Vec3>& sites) {
  Vec3 mean{0, 0, 0};
  BoundingBox box;
  for (const Vec3& p : leaf) {
    box.extend(p);
    for (int a = 0; a < 3; ++a) mean[a] += p[a];
  }
  for (auto& m : mean) m /= double(leaf.size());
  const Vec3 size = box.size();
  const int thinnest = size[0] <= size[1] && size[0] <= size[2] ? 0 : (size[1] <= size[2] ? 1 : 2);
  const double largest = std::max({size[0], size[1], size[2]});
  // A site at the mean of a flat patch lies on its surface, and the Delaunay tets between
  // such sites are slivers along it, each crossed by the surface: an object near the surface
  // met 38.6 shards a near step on the terrain. Two sites, one each side, make tets that
  // straddle the surface instead (docs/BENCHMARKS.md, "Sites beside flat patches": flatter
  // than half, and twice the patch away, measured best of 0.25, 0.5, 0.75 and every leaf, and
  // of 1, 1.5, 2 and 4). Kept within the mesh's box, whose corners bound it.
  constexpr double kFlat = 0.5, kLift = 2.0;
  if (leaf.size() > 1 && size[thinnest] < kFlat * largest) {
    for (const double side : {kLift, -kLift}) {
      Vec3 site = mean;
      site[thinnest] = std::clamp(mean[thinnest] + side * largest, bounds.lo[thinnest],
                                  bounds.hi[thinnest]);
      sites.push_back(site);
    }
    return;
  }
  sites.push_back(mean);
}

BoundingBox enlarged_bounds(const BoundingBox& bounds, double margin) {
  const Vec3 size = bounds.size();
  const double largest = std::max({size[0], size[1], size[2]});
  // A flat or point-like model still gets a box with volume.
  const double pad = std::max(margin * largest, largest > 0 ? 1e-3 * largest : 1.0);
  BoundingBox out;
  for (int a = 0; a < 3; ++a) {
    out.lo[a] = bounds.lo[a] - pad;
    out.hi[a] = bounds.hi[a] + pad;
  }
  return out;
}

std::vector<Vec3> sample_sites(std::span<Vec3> centroids, const BoundingBox& bounds,
                               const SamplingOptions& options) {
  if (centroids.empty()) throw InputError("sampling: the model has no triangle");
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(bounds.lo[a]) || !std::isfinite(bounds.hi[a]))
      throw InputError("sampling: the model's bounds are not finite");
  std::vector<Vec3> sites;
  const BoundingBox box = enlarged_bounds(bounds, options.margin);
  split(centroids, 0, centroids.size(), std::max<std::size_t>(1, options.leaf_triangles), box,
        sites);
  for (std::size_t i = 0; i < kBoxCornerSites; ++i)
    sites.push_back({(i & 1) ? box.hi[0] : box.lo[0], (i & 2) ? box.hi[1] : box.lo[1],
                     (i & 4) ? box.hi[2] : box.lo[2]});
  return sites;
}

TetMesh build_coarse_mesh(std::span<const Vec3> sites) {
  std::vector<std::pair<Kernel::Point_3, std::uint32_t>> points;
  points.reserve(sites.size());
  for (std::size_t i = 0; i < sites.size(); ++i)
    points.emplace_back(Kernel::Point_3(sites[i][0], sites[i][1], sites[i][2]),
                        static_cast<std::uint32_t>(i));
  Delaunay delaunay(points.begin(), points.end());
  if (delaunay.dimension() < 3)
    throw InputError("coarse mesh: the " + std::to_string(sites.size()) +
                     " sites span no volume (dimension " + std::to_string(delaunay.dimension()) +
                     ")");

  TetMesh mesh;
  // Renumber vertices densely (duplicate sites were merged by CGAL) in site order.
  std::vector<std::uint32_t> vertex_index(sites.size(), TetMesh::no_neighbour);
  std::vector<Delaunay::Vertex_handle> by_site(sites.size());
  for (auto v = delaunay.finite_vertices_begin(); v != delaunay.finite_vertices_end(); ++v)
    by_site[v->info()] = v;
  for (std::size_t i = 0; i < sites.size(); ++i) {
    if (by_site[i] == Delaunay::Vertex_handle()) continue;
    vertex_index[i] = static_cast<std::uint32_t>(mesh.vertices.size());
    mesh.vertices.push_back(sites[i]);
  }
  for (auto c = delaunay.finite_cells_begin(); c != delaunay.finite_cells_end(); ++c) {
    c->info() = static_cast<std::uint32_t>(mesh.tets.size());
    std::array<std::uint32_t, 4> corners;
    for (int i = 0; i < 4; ++i) corners[i] = vertex_index[c->vertex(i)->info()];
    mesh.tets.push_back(corners);
  }
  mesh.neighbours.resize(mesh.tets.size());
  for (auto c = delaunay.finite_cells_begin(); c != delaunay.finite_cells_end(); ++c) {
    auto& n = mesh.neighbours[c->info()];
    for (int i = 0; i < 4; ++i) {
      const auto neighbour = c->neighbor(i);
      n[i] = delaunay.is_infinite(neighbour) ? TetMesh::no_neighbour : neighbour->info();
    }
  }
  return mesh;
}

}  // namespace tetrapage
