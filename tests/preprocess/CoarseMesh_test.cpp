// The coarse mesh against exact predicates: orientation, neighbour symmetry, a tiling of the
// enlarged box, and the Delaunay empty-sphere property checked by brute force.

#include <gtest/gtest.h>

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/preprocess/CoarseMesh.h"
#include "tetrapage/tools/Random.h"

namespace tetrapage {
namespace {

using Exact = CGAL::Exact_predicates_exact_constructions_kernel;
Exact::Point_3 exact(const Vec3& v) { return {v[0], v[1], v[2]}; }

std::vector<Vec3> clustered_centroids(std::uint64_t seed, std::size_t count) {
  Random random(seed);
  std::vector<Vec3> points;
  // Two dense clusters and sparse noise: the sampler should put sites where they are.
  for (std::size_t i = 0; i < count; ++i) {
    const double which = random.uniform();
    const Vec3 centre = which < 0.45 ? Vec3{0.2, 0.2, 0.2} : which < 0.9 ? Vec3{0.7, 0.6, 0.8} : Vec3{0.5, 0.5, 0.5};
    const double spread = which < 0.9 ? 0.05 : 0.5;
    points.push_back({centre[0] + spread * (random.uniform() - 0.5), centre[1] + spread * (random.uniform() - 0.5),
                      centre[2] + spread * (random.uniform() - 0.5)});
  }
  return points;
}

TEST(SampleSites, OneOrTwoSitesPerLeafPlusTheBoxCorners) {
  auto centroids = clustered_centroids(3, 20000);
  BoundingBox bounds;
  for (const auto& c : centroids) bounds.extend(c);
  SamplingOptions options;
  options.leaf_triangles = 500;
  const auto sites = sample_sites(centroids, bounds, options);
  // A median split halves until a leaf holds at most 500: between 20000/500 and 2x that leaves,
  // each one site, or two when flat.
  EXPECT_GE(sites.size(), 40u + 8u);
  EXPECT_LE(sites.size(), 2 * 64u + 8u);
  const BoundingBox box = enlarged_bounds(bounds, options.margin);
  for (const auto& s : sites)
    for (int a = 0; a < 3; ++a) {
      EXPECT_GE(s[a], box.lo[a]);
      EXPECT_LE(s[a], box.hi[a]);
    }
  EXPECT_THROW(sample_sites({}, bounds, options), InputError);
}

// A terrain-like sample (a gently curved sheet): each leaf is flat, and gets one site above and
// one below its surface, symmetric about its mean, inside the mesh's box; a leaf with volume
// (the clusters above) keeps its mean.
TEST(SampleSites, FlatLeavesGetASiteEachSideOfTheirSurface) {
  Random random(7);
  std::vector<Vec3> centroids;
  for (int i = 0; i < 20000; ++i) {
    const double x = random.uniform(), y = random.uniform();
    centroids.push_back({x, y, 0.5 + 0.02 * std::sin(6 * x) * std::cos(5 * y)});
  }
  BoundingBox bounds;
  for (const auto& c : centroids) bounds.extend(c);
  SamplingOptions options;
  options.leaf_triangles = 500;
  const auto sites = sample_sites(centroids, bounds, options);
  const BoundingBox box = enlarged_bounds(bounds, options.margin);
  ASSERT_EQ((sites.size() - 8) % 2, 0u);
  ASSERT_GE(sites.size() - 8, 2u * 40);
  for (std::size_t i = 0; i + 8 < sites.size(); i += 2) {
    const Vec3 &above = sites[i], &below = sites[i + 1];
    EXPECT_EQ(above[0], below[0]);
    EXPECT_EQ(above[1], below[1]);
    EXPECT_GT(above[2], 0.52) << "site " << i;
    EXPECT_LT(below[2], 0.48) << "site " << i;
    EXPECT_LE(above[2], box.hi[2]);
    EXPECT_GE(below[2], box.lo[2]);
  }
  // Clustered centroids with volume: one site per leaf, as many as the split's leaves.
  auto clustered = clustered_centroids(3, 20000);
  std::vector<Vec3> one;
  append_leaf_sites(std::span<const Vec3>(clustered).subspan(0, 100), box, one);
  EXPECT_EQ(one.size(), 1u);
}

/// The sampler's median split, serial and depth first: the reference for the parallel one.
void split_serially(std::vector<Vec3>& points, std::size_t begin, std::size_t end, std::size_t leaf,
                    const BoundingBox& bounds, std::vector<Vec3>& sites) {
  if (end - begin <= leaf) {
    append_leaf_sites(std::span<const Vec3>(points).subspan(begin, end - begin), bounds, sites);
    return;
  }
  BoundingBox box;
  for (std::size_t i = begin; i < end; ++i) box.extend(points[i]);
  const Vec3 size = box.size();
  const int axis = size[0] >= size[1] && size[0] >= size[2] ? 0 : (size[1] >= size[2] ? 1 : 2);
  if (size[axis] == 0.0) {
    sites.push_back(points[begin]);
    return;
  }
  const std::size_t middle = begin + (end - begin) / 2;
  std::nth_element(points.begin() + long(begin), points.begin() + long(middle), points.begin() + long(end),
                   [axis](const Vec3& a, const Vec3& b) { return a[axis] < b[axis]; });
  split_serially(points, begin, middle, leaf, bounds, sites);
  split_serially(points, middle, end, leaf, bounds, sites);
}

TEST(SampleSites, TheSameSitesInTheSameOrderAsTheSerialSplit) {
  // Enough centroids that the halves are split on several threads (from 65,536 points), with
  // repeated coordinates (ties in the medians).
  auto centroids = clustered_centroids(5, 300000);
  for (std::size_t i = 0; i < centroids.size(); i += 3) centroids[i][0] = std::round(centroids[i][0] * 64) / 64;
  BoundingBox bounds;
  for (const auto& c : centroids) bounds.extend(c);
  SamplingOptions options;
  options.leaf_triangles = 700;
  std::vector<Vec3> points = centroids, expected;
  split_serially(points, 0, points.size(), options.leaf_triangles,
                 enlarged_bounds(bounds, options.margin), expected);
  const auto sites = sample_sites(centroids, bounds, options);
  ASSERT_EQ(sites.size(), expected.size() + 8);
  EXPECT_TRUE(std::equal(expected.begin(), expected.end(), sites.begin()));
}

TEST(CoarseMesh, IsAValidDelaunayTilingOfTheEnlargedBox) {
  const std::uint64_t seed = 11;
  SCOPED_TRACE("seed " + std::to_string(seed));
  auto centroids = clustered_centroids(seed, 5000);
  BoundingBox bounds;
  for (const auto& c : centroids) bounds.extend(c);
  SamplingOptions options;
  options.leaf_triangles = 50;
  const auto sites = sample_sites(centroids, bounds, options);
  const TetMesh mesh = build_coarse_mesh(sites);
  ASSERT_GT(mesh.tet_count(), sites.size());
  ASSERT_EQ(mesh.neighbours.size(), mesh.tet_count());

  Exact::FT volume = 0;
  std::size_t hull_faces = 0;
  for (std::size_t t = 0; t < mesh.tet_count(); ++t) {
    const auto c = mesh.corners(t);
    ASSERT_EQ(CGAL::orientation(exact(c[0]), exact(c[1]), exact(c[2]), exact(c[3])), CGAL::POSITIVE)
        << "tet " << t;
    volume += Exact::Tetrahedron_3(exact(c[0]), exact(c[1]), exact(c[2]), exact(c[3])).volume();
    for (int i = 0; i < 4; ++i) {
      const auto u = mesh.neighbours[t][i];
      if (u == TetMesh::no_neighbour) {
        ++hull_faces;
        continue;
      }
      // The neighbour across face i points back, and they share exactly that face.
      std::set<std::uint32_t> face;
      for (int k = 0; k < 4; ++k)
        if (k != i) face.insert(mesh.tets[t][k]);
      int back = -1;
      for (int j = 0; j < 4; ++j)
        if (mesh.neighbours[u][j] == t) back = j;
      ASSERT_GE(back, 0) << "tet " << t << " face " << i;
      std::set<std::uint32_t> other;
      for (int k = 0; k < 4; ++k)
        if (k != back) other.insert(mesh.tets[u][k]);
      ASSERT_EQ(face, other) << "tet " << t << " face " << i;
    }
  }
  const BoundingBox box = enlarged_bounds(bounds, options.margin);
  const Exact::FT box_volume = (Exact::FT(box.hi[0]) - box.lo[0]) * (Exact::FT(box.hi[1]) - box.lo[1]) *
                               (Exact::FT(box.hi[2]) - box.lo[2]);
  EXPECT_EQ(volume, box_volume) << "the tets must tile the enlarged box exactly";
  EXPECT_GE(hull_faces, 12u);  // each of the box's six faces is cut into at least two triangles

  // Empty spheres: no site strictly inside any tet's circumsphere (a sample of tets).
  for (std::size_t t = 0; t < mesh.tet_count(); t += 7) {
    const auto c = mesh.corners(t);
    for (const auto& v : mesh.vertices)
      ASSERT_NE(CGAL::side_of_bounded_sphere(exact(c[0]), exact(c[1]), exact(c[2]), exact(c[3]), exact(v)),
                CGAL::ON_BOUNDED_SIDE)
          << "tet " << t;
  }
}

TEST(CoarseMesh, FlatModelsStillGetAVolume) {
  // All centroids on the plane z = 0.5: the enlarged box keeps a thickness.
  std::vector<Vec3> centroids;
  for (int i = 0; i < 100; ++i) centroids.push_back({i * 0.01, (i * 37 % 100) * 0.01, 0.5});
  BoundingBox bounds;
  for (const auto& c : centroids) bounds.extend(c);
  const auto sites = sample_sites(centroids, bounds, SamplingOptions{10, 0.05});
  const TetMesh mesh = build_coarse_mesh(sites);
  EXPECT_GT(mesh.tet_count(), 0u);
}

TEST(CoarseMesh, RejectsSitesWithoutVolume) {
  const std::vector<Vec3> coplanar{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  EXPECT_THROW(build_coarse_mesh(coplanar), InputError);
}

}  // namespace
}  // namespace tetrapage
