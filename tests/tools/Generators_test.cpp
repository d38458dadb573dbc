// The study's generators (random BSP, scenes, tetras, terrains, flying objects) against
// brute-force checks: tiling by point sampling and pairwise overlap tests, closedness by edge
// pairing, orientation by CGAL's exact orientation predicate, and byte-for-byte determinism.
// Open and closed scene copies are told apart in the written file, by components of shared
// vertex positions and edge parity, independently of the generator's summary.

#include <gtest/gtest.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <numeric>
#include <string>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/tools/BspPartition.h"
#include "tetrapage/tools/MeshLibrary.h"
#include "tetrapage/tools/ObjectGenerator.h"
#include "tetrapage/tools/Random.h"
#include "tetrapage/tools/SceneGenerator.h"
#include "tetrapage/tools/TerrainGenerator.h"
#include "tetrapage/tools/TetrasGenerator.h"

#include "RunCli.h"
#include "TestFiles.h"

namespace tetrapage {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;

std::filesystem::path test_folder(const std::string& name) {
  return test::fresh_folder("generators", name);
}

using test::file_bytes;

double volume(const BoundingBox& box) {
  const Vec3 s = box.size();
  return s[0] * s[1] * s[2];
}

// Open interiors intersect (sharing a face is fine).
bool interiors_overlap(const BoundingBox& a, const BoundingBox& b) {
  for (int k = 0; k < 3; ++k)
    if (!(a.lo[k] < b.hi[k] && b.lo[k] < a.hi[k])) return false;
  return true;
}

bool contains(const BoundingBox& outer, const BoundingBox& inner) {
  for (int k = 0; k < 3; ++k)
    if (inner.lo[k] < outer.lo[k] || inner.hi[k] > outer.hi[k]) return false;
  return true;
}

Kernel::Point_3 point(const Vec3& v) {
  return {v[0], v[1], v[2]};
}

// Every directed edge appears once, and so does its reverse: closed and consistently oriented.
bool closed_and_consistent(const std::vector<TriangleIndices>& triangles) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
  for (const auto& t : triangles)
    for (int i = 0; i < 3; ++i) ++edges[{t[i], t[(i + 1) % 3]}];
  for (const auto& [edge, count] : edges) {
    if (count != 1) return false;
    const auto reverse = edges.find({edge.second, edge.first});
    if (reverse == edges.end() || reverse->second != 1) return false;
  }
  return true;
}

// Six times the signed volume enclosed (divergence theorem); > 0 when faces point outward.
double signed_volume6(const std::vector<Vec3>& vertices,
                      const std::vector<TriangleIndices>& triangles) {
  double sum = 0.0;
  for (const auto& t : triangles) {
    const Vec3 &a = vertices[t[0]], &b = vertices[t[1]], &c = vertices[t[2]];
    sum += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
           a[2] * (b[0] * c[1] - b[1] * c[0]);
  }
  return sum;
}

// Connected components of a soup by shared vertex indices: triangle lists per component.
std::vector<std::vector<std::size_t>> components(const TriangleSoup& soup) {
  std::vector<std::uint32_t> parent(soup.vertices.size());
  std::iota(parent.begin(), parent.end(), 0u);
  const auto find = [&](std::uint32_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (const auto& t : soup.triangles) {
    parent[find(t[1])] = find(t[0]);
    parent[find(t[2])] = find(t[0]);
  }
  std::map<std::uint32_t, std::vector<std::size_t>> by_root;
  for (std::size_t t = 0; t < soup.triangles.size(); ++t)
    by_root[find(soup.triangles[t][0])].push_back(t);
  std::vector<std::vector<std::size_t>> result;
  for (auto& [root, list] : by_root) result.push_back(std::move(list));
  return result;
}

struct ComponentCount {
  std::size_t closed = 0, open = 0;
};

// Connected components of a soup by shared vertex POSITION (whatever the reader does with
// equal vertices), each closed when every undirected edge in it is used an even number of
// times, open otherwise.
ComponentCount closed_and_open_components(const TriangleSoup& soup) {
  std::map<Vec3, std::uint32_t> position_ids;
  std::vector<std::uint32_t> id(soup.vertices.size());
  for (std::size_t v = 0; v < soup.vertices.size(); ++v) {
    const auto next = static_cast<std::uint32_t>(position_ids.size());
    id[v] = position_ids.emplace(soup.vertices[v], next).first->second;
  }
  std::vector<std::uint32_t> parent(position_ids.size());
  std::iota(parent.begin(), parent.end(), 0u);
  const auto find = [&](std::uint32_t p) {
    while (parent[p] != p) p = parent[p] = parent[parent[p]];
    return p;
  };
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> edge_uses;
  for (const auto& t : soup.triangles) {
    parent[find(id[t[1]])] = find(id[t[0]]);
    parent[find(id[t[2]])] = find(id[t[0]]);
    for (int i = 0; i < 3; ++i) {
      const auto [a, b] = std::minmax(id[t[i]], id[t[(i + 1) % 3]]);
      ++edge_uses[{a, b}];
    }
  }
  std::map<std::uint32_t, bool> open_by_root;  // every component holding a triangle
  for (const auto& t : soup.triangles) open_by_root.emplace(find(id[t[0]]), false);
  for (const auto& [edge, uses] : edge_uses)
    if (uses % 2 != 0) open_by_root[find(edge.first)] = true;
  ComponentCount count;
  for (const auto& [root, open] : open_by_root) ++(open ? count.open : count.closed);
  return count;
}

TriangleSoup box_soup(const Vec3& lo, const Vec3& hi) {
  TriangleSoup soup;
  for (int i = 0; i < 8; ++i)
    soup.vertices.push_back(
        {(i & 1) ? hi[0] : lo[0], (i & 2) ? hi[1] : lo[1], (i & 4) ? hi[2] : lo[2]});
  soup.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                    {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  soup.part_of.assign(12, 0);
  soup.part_names = {"box"};
  return soup;
}

TriangleSoup octahedron_soup() {
  TriangleSoup soup;
  soup.vertices = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  soup.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                    {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  soup.part_of.assign(8, 0);
  soup.part_names = {"octahedron"};
  return soup;
}

TriangleSoup tetra_soup() {
  TriangleSoup soup;
  soup.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  soup.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  soup.part_of.assign(4, 0);
  soup.part_names = {"tetra"};
  return soup;
}

LibraryMesh library_mesh(std::string name, TriangleSoup soup) {
  LibraryMesh mesh;
  mesh.name = std::move(name);
  mesh.soup = std::move(soup);
  return mesh;
}

// Three small closed meshes (12, 8 and 4 triangles): scenes of many copies stay tiny.
MeshLibrary small_library() {
  std::vector<LibraryMesh> meshes;
  meshes.push_back(library_mesh("box", box_soup({0, 0, 0}, {3, 1, 2})));
  meshes.push_back(library_mesh("octahedron", octahedron_soup()));
  meshes.push_back(library_mesh("tetra", tetra_soup()));
  return MeshLibrary(std::move(meshes));
}

void write_off(const std::filesystem::path& path, const TriangleSoup& soup) {
  std::ofstream out(path);
  out << "OFF\n" << soup.vertices.size() << ' ' << soup.triangles.size() << " 0\n";
  for (const auto& v : soup.vertices) out << v[0] << ' ' << v[1] << ' ' << v[2] << '\n';
  for (const auto& t : soup.triangles) out << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
}

// ---------------------------------------------------------------------------------------------
// Random BSP

struct BspCase {
  BoundingBox box;
  std::size_t leaves;
  std::uint64_t seed;
};

TEST(BspPartition, LeavesTileTheBoxAndRespectAlpha) {
  const BoundingBox unit{{0, 0, 0}, {1, 1, 1}};
  const BoundingBox odd{{-3, 0, 2}, {5, 1, 2.5}};
  for (const BspCase& c : {BspCase{unit, 1, 1}, BspCase{unit, 2, 2}, BspCase{unit, 7, 3},
                           BspCase{unit, 100, 4}, BspCase{unit, 1000, 5}, BspCase{odd, 300, 6}}) {
    SCOPED_TRACE("leaves " + std::to_string(c.leaves) + ", seed " + std::to_string(c.seed));
    Random random(c.seed);
    const BspPartition bsp = random_bsp_partition(c.box, c.leaves, random);
    ASSERT_EQ(bsp.leaves.size(), c.leaves);
    EXPECT_DOUBLE_EQ(bsp.alpha, 0.8 * 0.5 * std::cbrt(volume(c.box) / double(c.leaves)));

    double total = 0.0;
    for (const auto& leaf : bsp.leaves) {
      EXPECT_TRUE(contains(c.box, leaf));
      total += volume(leaf);
      // The alpha rule: a split never leaves a side shorter than alpha; an axis never split
      // keeps the box's side.
      for (int a = 0; a < 3; ++a) {
        const double side = leaf.hi[a] - leaf.lo[a];
        const double box_side = c.box.hi[a] - c.box.lo[a];
        EXPECT_GE(side, std::min(box_side, bsp.alpha) * (1 - 1e-12)) << "axis " << a;
      }
    }
    EXPECT_NEAR(total, volume(c.box), 1e-12 * volume(c.box));
    for (std::size_t i = 0; i < bsp.leaves.size(); ++i)
      for (std::size_t j = i + 1; j < bsp.leaves.size(); ++j)
        ASSERT_FALSE(interiors_overlap(bsp.leaves[i], bsp.leaves[j])) << i << " vs " << j;

    // Independent check of the tiling: random points lie in exactly one leaf.
    Random points(c.seed + 1000);
    for (int p = 0; p < 2000; ++p) {
      Vec3 x;
      for (int a = 0; a < 3; ++a) x[a] = points.uniform(c.box.lo[a], c.box.hi[a]);
      int inside = 0;
      for (const auto& leaf : bsp.leaves) {
        bool in = true;
        for (int a = 0; a < 3; ++a) in = in && leaf.lo[a] <= x[a] && x[a] < leaf.hi[a];
        inside += in ? 1 : 0;
      }
      ASSERT_EQ(inside, 1) << "point " << x[0] << ' ' << x[1] << ' ' << x[2];
    }
  }
}

TEST(BspPartition, SameSeedSameLeavesOtherSeedOthers) {
  const BoundingBox unit{{0, 0, 0}, {1, 1, 1}};
  Random a(42), b(42), c(43);
  const auto first = random_bsp_partition(unit, 200, a).leaves;
  const auto second = random_bsp_partition(unit, 200, b).leaves;
  const auto third = random_bsp_partition(unit, 200, c).leaves;
  bool same = true, differs = false;
  for (std::size_t i = 0; i < first.size(); ++i) {
    same = same && first[i].lo == second[i].lo && first[i].hi == second[i].hi;
    differs = differs || first[i].lo != third[i].lo || first[i].hi != third[i].hi;
  }
  EXPECT_TRUE(same);
  EXPECT_TRUE(differs);
}

TEST(BspPartition, RejectsBadArguments) {
  const BoundingBox unit{{0, 0, 0}, {1, 1, 1}};
  Random random(1);
  EXPECT_DOUBLE_EQ(bsp_alpha_bound(unit, 1000), 0.05);
  EXPECT_THROW(random_bsp_partition(unit, 0, random), InputError);
  EXPECT_THROW(random_bsp_partition(unit, 1000, random, 0.05), InputError);  // at the bound
  EXPECT_THROW(random_bsp_partition(unit, 1000, random, 0.0), InputError);
  EXPECT_THROW(random_bsp_partition(BoundingBox{}, 10, random), InputError);
  EXPECT_THROW(random_bsp_partition(BoundingBox{{0, 0, 0}, {1, 0, 1}}, 10, random), InputError);
  // Just below the bound the process still reaches the count (it can never get stuck).
  EXPECT_EQ(random_bsp_partition(unit, 1000, random, 0.0499).leaves.size(), 1000u);
}

// ---------------------------------------------------------------------------------------------
// Mesh library

TEST(MeshLibrary, LoadsEveryMeshOfAFolderSortedAndSkipsBadFiles) {
  const auto folder = test_folder("library");
  write_off(folder / "b_octahedron.off", octahedron_soup());
  write_off(folder / "a_box.off", box_soup({0, 0, 0}, {1, 1, 1}));
  write_off(folder / "c_tetra.OFF", tetra_soup());
  std::ofstream(folder / "broken.off") << "OFF\n3 1 0\n0 0 0\n1 0\n";
  std::ofstream(folder / "notes.txt") << "not a mesh\n";

  const MeshLibrary library = MeshLibrary::load_folder(folder);
  ASSERT_EQ(library.size(), 3u);
  EXPECT_EQ(library[0].name, "a_box");
  EXPECT_EQ(library[1].name, "b_octahedron");
  EXPECT_EQ(library[2].name, "c_tetra");
  EXPECT_EQ(library[0].triangle_count(), 12u);
  EXPECT_EQ(library.total_triangles(), 24u);
  EXPECT_EQ(library.smallest_triangle_count(), 4u);
  EXPECT_EQ(library.largest_triangle_count(), 12u);
  ASSERT_EQ(library.skipped().size(), 1u);
  EXPECT_NE(library.skipped()[0].find("broken.off"), std::string::npos);
}

TEST(MeshLibrary, FolderWithoutUsableMeshIsAClearError) {
  const auto folder = test_folder("empty_library");
  std::ofstream(folder / "broken.off") << "this is not OFF\n";
  try {
    MeshLibrary::load_folder(folder);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--meshes"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("make deps"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("broken.off"), std::string::npos) << e.what();
  }
  EXPECT_THROW(MeshLibrary::load_folder(folder / "missing"), InputError);
  EXPECT_THROW(MeshLibrary(std::vector<LibraryMesh>{}), InputError);
}

TEST(MeshLibrary, DefaultIsTheCuratedSetAndTheEnvironmentOverridesIt) {
  // The test owns the variable while it runs; a value set by the caller is put back.
  const char* outer = std::getenv("TETRAPAGE_MESH_DIR");
  const std::string saved = outer != nullptr ? outer : "";
  unsetenv("TETRAPAGE_MESH_DIR");
  const MeshLibrary library = MeshLibrary::load_default();
  ASSERT_GE(library.size(), 1u) << "folder " << MeshLibrary::default_folder();
  const auto curated = MeshLibrary::curated_names();
  for (std::size_t m = 0; m < library.size(); ++m) {
    EXPECT_NE(std::find(curated.begin(), curated.end(), library[m].name), curated.end())
        << library[m].name;
    if (m > 0) {
      EXPECT_LT(library[m - 1].name, library[m].name);
    }
  }

  const auto folder = test_folder("environment_library");
  write_off(folder / "own.off", octahedron_soup());
  ASSERT_EQ(setenv("TETRAPAGE_MESH_DIR", folder.c_str(), 1), 0);
  EXPECT_EQ(MeshLibrary::default_folder(), folder);
  const MeshLibrary own = MeshLibrary::load_default();
  if (outer != nullptr) {
    setenv("TETRAPAGE_MESH_DIR", saved.c_str(), 1);
  } else {
    unsetenv("TETRAPAGE_MESH_DIR");
  }
  ASSERT_EQ(own.size(), 1u);
  EXPECT_EQ(own[0].name, "own");
}

// ---------------------------------------------------------------------------------------------
// Scenes

TEST(SceneGenerator, PlanReachesTheTarget) {
  const MeshLibrary library = small_library();
  for (std::uint64_t target : {1u, 3u, 4u, 5u, 11u, 100u, 12345u}) {
    Random random(target);
    const auto plan = plan_scene_copies(library, target, 0.0, random);
    std::uint64_t total = 0;
    for (const auto& copy : plan) {
      EXPECT_FALSE(copy.open);
      EXPECT_EQ(copy.triangles, library[copy.mesh].triangle_count());
      total += copy.triangles;
    }
    ASSERT_FALSE(plan.empty());
    // Within half the smallest mesh (4 triangles), or one smallest mesh for a tiny target.
    EXPECT_LE(std::llabs(std::int64_t(total) - std::int64_t(target)), target < 4 ? 3 : 2)
        << "target " << target;
  }
}

TEST(SceneGenerator, CopiesSitInDisjointLeavesInsideTheUnitCube) {
  const MeshLibrary library = small_library();
  const auto folder = test_folder("scene");
  SceneOptions options;
  options.triangles = 3000;
  options.seed = 7;
  SceneSummary summary;
  {
    MeshWriter writer(folder / "a.ply");
    summary = generate_scene(library, options, writer);
    writer.commit();
  }
  EXPECT_LE(std::llabs(std::int64_t(summary.triangles) - 3000), 2);
  EXPECT_EQ(summary.leaves, 2 * summary.copies.size());
  // SceneOptions opens no copy unless asked (library callers keep closed obstacles).
  EXPECT_EQ(summary.open_copies, 0u);
  EXPECT_EQ(summary.closed_copies, summary.copies.size());
  const BoundingBox unit{{0, 0, 0}, {1, 1, 1}};
  std::uint64_t triangles = 0;
  for (std::size_t i = 0; i < summary.copies.size(); ++i) {
    const SceneCopy& copy = summary.copies[i];
    triangles += copy.triangles;
    EXPECT_EQ(copy.triangles, library[copy.mesh].triangle_count());
    ASSERT_TRUE(contains(unit, copy.leaf));
    ASSERT_TRUE(contains(copy.leaf, copy.placed)) << "copy " << i;
    // Fitted: `fill` of the leaf along the tightest axis, centred.
    double tightest = 0.0;
    for (int a = 0; a < 3; ++a) {
      tightest = std::max(tightest, copy.placed.size()[a] / copy.leaf.size()[a]);
      EXPECT_NEAR(copy.placed.center()[a], copy.leaf.center()[a], 1e-12);
    }
    EXPECT_NEAR(tightest, options.fill, 1e-9) << "copy " << i;
    for (std::size_t j = i + 1; j < summary.copies.size(); ++j) {
      ASSERT_FALSE(interiors_overlap(copy.leaf, summary.copies[j].leaf)) << i << " vs " << j;
      ASSERT_FALSE(interiors_overlap(copy.placed, summary.copies[j].placed)) << i << " vs " << j;
    }
  }
  EXPECT_EQ(triangles, summary.triangles);

  // The file holds exactly what the summary says, inside the unit cube.
  const TriangleSoup soup = read_mesh(folder / "a.ply");
  EXPECT_EQ(soup.triangle_count(), summary.triangles);
  for (const auto& v : soup.vertices) {
    bool in_some_copy = false;
    for (const auto& copy : summary.copies) {
      bool in = true;
      for (int a = 0; a < 3; ++a) in = in && copy.placed.lo[a] <= v[a] && v[a] <= copy.placed.hi[a];
      in_some_copy = in_some_copy || in;
    }
    ASSERT_TRUE(in_some_copy) << v[0] << ' ' << v[1] << ' ' << v[2];
  }
  // Each copy is a closed mesh here, so the whole scene is closed and outward oriented.
  EXPECT_TRUE(closed_and_consistent(soup.triangles));
  EXPECT_GT(signed_volume6(soup.vertices, soup.triangles), 0.0);
}

TEST(SceneGenerator, SameSeedSameBytesOtherSeedOtherBytes) {
  const MeshLibrary library = small_library();
  const auto folder = test_folder("scene_determinism");
  const auto write = [&](const std::string& name, std::uint64_t seed) {
    SceneOptions options;
    options.triangles = 500;
    options.seed = seed;
    MeshWriter writer(folder / name);
    generate_scene(library, options, writer);
    writer.commit();
    return file_bytes(folder / name);
  };
  const std::string a = write("a.ply", 11), b = write("b.ply", 11), c = write("c.ply", 12);
  EXPECT_FALSE(a.empty());
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
}

TEST(SceneGenerator, RealMeshesReachTheTarget) {
  const MeshLibrary library = MeshLibrary::load_default();
  const auto folder = test_folder("scene_real");
  SceneOptions options;
  options.triangles = 40000;
  options.seed = 3;
  MeshWriter writer(folder / "scene.ply");
  const SceneSummary summary = generate_scene(library, options, writer);
  writer.commit();
  const double half_smallest = 0.5 * double(library.smallest_triangle_count());
  EXPECT_LE(std::abs(double(summary.triangles) - 40000.0), half_smallest)
      << summary.copies.size() << " copies";
  const TriangleSoup soup = read_mesh(folder / "scene.ply");
  EXPECT_EQ(soup.triangle_count(), summary.triangles);
  const BoundingBox bounds = soup.bounds();
  EXPECT_TRUE(contains(BoundingBox{{0, 0, 0}, {1, 1, 1}}, bounds));
}

// Curated meshes are one connected piece each; with another library a closed copy may be
// several closed components.
bool every_mesh_is_one_piece(const MeshLibrary& library) {
  for (const auto& mesh : library.meshes())
    if (components(mesh.soup).size() != 1) return false;
  return true;
}

// A real-mesh scene of about 20,000 triangles in one PLY file, as a CAD export would hold it.
SceneSummary write_real_scene(const MeshLibrary& library, const std::filesystem::path& path,
                              double open_fraction, std::uint64_t seed) {
  SceneOptions options;
  options.triangles = 20000;
  options.seed = seed;
  options.open_fraction = open_fraction;
  MeshWriter writer(path);
  SceneSummary summary = generate_scene(library, options, writer);
  writer.commit();
  return summary;
}

TEST(SceneGenerator, PlanCountsTheTrianglesOpenedCopiesKeep) {
  const MeshLibrary library = MeshLibrary::load_default();
  const double half_smallest = 0.5 * double(library.smallest_triangle_count());
  for (double fraction : {default_scene_open_fraction, 1.0}) {
    for (std::uint64_t target : {5000u, 40000u, 200000u}) {
      SCOPED_TRACE("fraction " + std::to_string(fraction) + ", target " + std::to_string(target));
      Random random(target);
      const auto plan = plan_scene_copies(library, target, fraction, random);
      std::uint64_t total = 0;
      std::size_t open = 0;
      for (const auto& copy : plan) {
        total += copy.triangles;
        open += copy.open ? 1 : 0;
        const std::uint64_t whole = library[copy.mesh].triangle_count();
        if (copy.open) {
          EXPECT_LT(copy.triangles, whole);
          EXPECT_GT(copy.triangles, 0u);
          EXPECT_GE(copy.cut.height, 0.6);
          EXPECT_LE(copy.cut.height, 0.9);
        } else {
          EXPECT_EQ(copy.triangles, whole);
        }
      }
      EXPECT_LE(std::abs(double(total) - double(target)), half_smallest) << plan.size();
      // Stratified: never more than the fraction rounded up; a cut that misses every triangle
      // leaves a copy closed, which is rare with real meshes.
      const double expected = fraction * double(plan.size());
      EXPECT_LE(double(open), std::ceil(expected));
      EXPECT_GE(double(open), std::floor(expected) - 0.1 * double(plan.size()) - 1.0);
    }
  }
}

TEST(SceneGenerator, DefaultMixesOpenAndClosedCopiesInOneFile) {
  const MeshLibrary library = MeshLibrary::load_default();
  const auto folder = test_folder("scene_open");
  // Seed 11: eight copies, two of them opened (any plan of four copies or more opens some).
  const SceneSummary summary =
      write_real_scene(library, folder / "a.ply", default_scene_open_fraction, 11);
  EXPECT_LE(std::abs(double(summary.triangles) - 20000.0), 2000.0);
  EXPECT_EQ(summary.open_copies + summary.closed_copies, summary.copies.size());
  ASSERT_GE(summary.open_copies, 1u);
  ASSERT_GE(summary.closed_copies, 1u);
  std::uint64_t triangles = 0;
  for (const SceneCopy& copy : summary.copies) {
    triangles += copy.triangles;
    if (copy.open) {
      EXPECT_LT(copy.triangles, library[copy.mesh].triangle_count());
    } else {
      EXPECT_EQ(copy.triangles, library[copy.mesh].triangle_count());
    }
    // Opened copies are placed as whole ones: inside their leaf, fitted along one axis.
    EXPECT_TRUE(contains(copy.leaf, copy.placed));
    double tightest = 0.0;
    for (int a = 0; a < 3; ++a)
      tightest = std::max(tightest, copy.placed.size()[a] / copy.leaf.size()[a]);
    EXPECT_NEAR(tightest, 0.9, 1e-9);
  }
  EXPECT_EQ(triangles, summary.triangles);

  // Independently of the summary: the file read back, split into components.
  const TriangleSoup soup = read_mesh(folder / "a.ply");
  ASSERT_EQ(soup.triangle_count(), summary.triangles);
  const ComponentCount found = closed_and_open_components(soup);
  EXPECT_GE(found.open, 1u);
  EXPECT_GE(found.closed, 1u);
  // An opened copy keeps one connected piece of its mesh: one open component each.
  EXPECT_EQ(found.open, summary.open_copies);
  // A closed copy is as many closed components as its mesh has pieces: one for the curated set.
  EXPECT_GE(found.closed, summary.closed_copies);
  if (every_mesh_is_one_piece(library)) {
    EXPECT_EQ(found.closed, summary.closed_copies);
  }

  // Same seed, same bytes; the opening changes them.
  write_real_scene(library, folder / "b.ply", default_scene_open_fraction, 11);
  write_real_scene(library, folder / "c.ply", 0.0, 11);
  const std::string a = file_bytes(folder / "a.ply");
  EXPECT_EQ(a, file_bytes(folder / "b.ply"));
  EXPECT_NE(a, file_bytes(folder / "c.ply"));
}

TEST(SceneGenerator, OpenFractionZeroKeepsEveryCopyClosed) {
  const MeshLibrary library = MeshLibrary::load_default();
  const auto folder = test_folder("scene_closed");
  const SceneSummary summary = write_real_scene(library, folder / "scene.ply", 0.0, 11);
  EXPECT_EQ(summary.open_copies, 0u);
  EXPECT_EQ(summary.closed_copies, summary.copies.size());
  const ComponentCount found = closed_and_open_components(read_mesh(folder / "scene.ply"));
  EXPECT_EQ(found.open, 0u);
  EXPECT_GE(found.closed, summary.copies.size());
}

TEST(SceneGenerator, OpenFractionOutOfRangeIsAnInputError) {
  const MeshLibrary library = small_library();
  const auto folder = test_folder("scene_bad_fraction");
  for (double fraction : {-0.1, 1.5, std::nan("")}) {
    SceneOptions options;
    options.open_fraction = fraction;
    MeshWriter writer(folder / "scene.ply");
    try {
      generate_scene(library, options, writer);
      FAIL() << "expected InputError for " << fraction;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("--open-fraction"), std::string::npos) << e.what();
    }
    Random random(1);
    EXPECT_THROW(plan_scene_copies(library, 100, fraction, random), InputError);
  }
  for (double fraction : {0.0, 1.0}) {  // the bounds are accepted
    SceneOptions options;
    options.triangles = 200;
    options.open_fraction = fraction;
    MeshWriter writer(folder / "scene.ply");
    EXPECT_FALSE(generate_scene(library, options, writer).copies.empty());
  }
}

TEST(SceneGenerator, CommandDefaultsToAMixAndReportsIt) {
  const auto folder = test_folder("scene_command");
  const auto scene = folder / "scene.ply", report = folder / "scene.json";
  std::string out;
  ASSERT_EQ(test::run_cli("generate scene --triangles 20000 --seed 11 -o " + scene.string() +
                              " --report " + report.string(),
                          out),
            0)
      << out;
  EXPECT_NE(out.find(" open, "), std::string::npos) << out;
  std::ifstream in(report);
  const auto json = nlohmann::json::parse(in);
  EXPECT_EQ(json.at("open_fraction").get<double>(), default_scene_open_fraction);
  const auto open = json.at("open_copies").get<std::size_t>();
  const auto closed = json.at("closed_copies").get<std::size_t>();
  EXPECT_EQ(open + closed, json.at("copies").get<std::size_t>());
  const ComponentCount found = closed_and_open_components(read_mesh(scene));
  EXPECT_GE(found.open, 1u);
  EXPECT_EQ(found.open, open);

  EXPECT_NE(
      test::run_cli("generate scene --open-fraction 1.5 -o " + (folder / "bad.ply").string(), out),
      0);
  EXPECT_FALSE(std::filesystem::exists(folder / "bad.ply"));
  ASSERT_EQ(test::run_cli("generate scene --help", out), 0);
  EXPECT_NE(out.find("--open-fraction"), std::string::npos) << out;
  EXPECT_NE(out.find("0.25"), std::string::npos) << out;
}

// What `generate scene` says it wrote and what `mesh info` reads back agree on the parts: one
// per copy (the report's count) where the format holds parts, one where it merges them (and
// says so); `mesh convert` keeps them or says it merged them.
TEST(SceneGenerator, PartsSurviveTheFileAndConversions) {
  const auto folder = test_folder("scene_parts");
  const auto parts_of = [&](const std::filesystem::path& file) {
    std::string out;
    const auto report = folder / "info.json";
    EXPECT_EQ(test::run_cli("mesh info " + file.string() + " --report " + report.string(), out), 0);
    std::ifstream in(report);
    return nlohmann::json::parse(in).at("files").at(0).at("parts").get<std::size_t>();
  };
  const auto said = [](const std::string& out) {  // "scene: N triangles, V vertices, P parts"
    const auto end = out.find(" parts", out.find("scene: "));
    const auto begin = out.rfind(", ", end) + 2;
    return std::stoul(out.substr(begin, end - begin));
  };
  std::size_t copies = 0;
  for (const std::string extension : {".ply", ".obj", ".glb", ".stl", ".off"}) {
    SCOPED_TRACE(extension);
    const auto scene = folder / ("scene" + extension), report = folder / "scene.json";
    std::string out;
    ASSERT_EQ(test::run_cli("generate scene --triangles 3000 --seed 4 -o " + scene.string() +
                                " --report " + report.string(),
                            out),
              0);
    std::ifstream in(report);
    copies = nlohmann::json::parse(in).at("copies").get<std::size_t>();
    ASSERT_GT(copies, 1u);
    const bool merged = extension == ".stl" || extension == ".off";
    EXPECT_EQ(said(out), merged ? 1u : copies) << out;
    EXPECT_EQ(parts_of(scene), merged ? 1u : copies);
    EXPECT_EQ(out.find("merged into one") != std::string::npos, merged) << out;
  }
  std::string out;
  ASSERT_EQ(test::run_cli("mesh convert " + (folder / "scene.ply").string() + " -o " +
                              (folder / "back.obj").string(),
                          out),
            0);
  EXPECT_EQ(out.find("merged"), std::string::npos) << out;
  EXPECT_EQ(parts_of(folder / "back.obj"), copies);
  ASSERT_EQ(test::run_cli("mesh convert " + (folder / "back.obj").string() + " -o " +
                              (folder / "flat.off").string(),
                          out),
            0);
  EXPECT_NE(out.find("the " + std::to_string(copies) + " parts were merged into one"),
            std::string::npos)
      << out;
  EXPECT_EQ(parts_of(folder / "flat.off"), 1u);
}

// ---------------------------------------------------------------------------------------------
// Tetras

TEST(TetrasGenerator, ClosedOutwardDisjointTetrahedra) {
  const auto folder = test_folder("tetras");
  TetrasOptions options;
  options.triangles = 400;
  options.seed = 5;
  TetrasSummary summary;
  {
    MeshWriter writer(folder / "tetras.ply");
    summary = generate_tetras(options, writer);
    writer.commit();
  }
  EXPECT_EQ(summary.tetras, 100u);
  EXPECT_EQ(summary.triangles, 400u);
  EXPECT_EQ(summary.leaves, 200u);

  const TriangleSoup soup = read_mesh(folder / "tetras.ply");
  ASSERT_EQ(soup.triangle_count(), 400u);
  const auto parts = components(soup);
  ASSERT_EQ(parts.size(), 100u);
  std::vector<BoundingBox> boxes;
  for (const auto& part : parts) {
    ASSERT_EQ(part.size(), 4u);
    std::vector<TriangleIndices> faces;
    std::vector<std::uint32_t> corners;
    for (auto t : part) {
      faces.push_back(soup.triangles[t]);
      corners.insert(corners.end(), soup.triangles[t].begin(), soup.triangles[t].end());
    }
    std::sort(corners.begin(), corners.end());
    corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
    ASSERT_EQ(corners.size(), 4u);
    EXPECT_TRUE(closed_and_consistent(faces));
    BoundingBox box;
    for (auto v : corners) box.extend(soup.vertices[v]);
    boxes.push_back(box);
    EXPECT_TRUE(contains(BoundingBox{{0, 0, 0}, {1, 1, 1}}, box));
    // Outward, decided exactly: the corner a face omits is on its negative side.
    for (const auto& f : faces) {
      const auto other = *std::find_if(corners.begin(), corners.end(), [&](std::uint32_t v) {
        return v != f[0] && v != f[1] && v != f[2];
      });
      EXPECT_EQ(CGAL::orientation(point(soup.vertices[f[0]]), point(soup.vertices[f[1]]),
                                  point(soup.vertices[f[2]]), point(soup.vertices[other])),
                CGAL::NEGATIVE);
    }
    std::vector<Vec3> local;
    std::vector<TriangleIndices> local_faces;
    for (const auto& f : faces) {
      TriangleIndices g{};
      for (int i = 0; i < 3; ++i) {
        g[i] = std::uint32_t(local.size());
        local.push_back(soup.vertices[f[i]]);
      }
      local_faces.push_back(g);
    }
    EXPECT_GT(signed_volume6(local, local_faces), 0.0);
  }
  for (std::size_t i = 0; i < boxes.size(); ++i)
    for (std::size_t j = i + 1; j < boxes.size(); ++j)
      ASSERT_FALSE(interiors_overlap(boxes[i], boxes[j])) << i << " vs " << j;
}

TEST(TetrasGenerator, SameSeedSameBytesOtherSeedOtherBytes) {
  const auto folder = test_folder("tetras_determinism");
  const auto write = [&](const std::string& name, std::uint64_t seed) {
    TetrasOptions options;
    options.triangles = 1000;
    options.seed = seed;
    MeshWriter writer(folder / name);
    generate_tetras(options, writer);
    writer.commit();
    return file_bytes(folder / name);
  };
  const std::string a = write("a.off", 2), b = write("b.off", 2), c = write("c.off", 3);
  EXPECT_FALSE(a.empty());
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
}

// ---------------------------------------------------------------------------------------------
// Terrains

TEST(TerrainGenerator, SampleCountFollowsTheTriangleCount) {
  EXPECT_EQ(terrain_samples_per_side(28322), 120u);     // the study's 120 x 120
  EXPECT_EQ(terrain_samples_per_side(2880000), 1201u);  // the full DEM
  EXPECT_EQ(terrain_samples_per_side(1), 2u);
  EXPECT_EQ(terrain_samples_per_side(2), 2u);
  // Brute force: the chosen s minimises |2 (s-1)^2 - N|.
  for (std::uint64_t n : {3u, 50u, 968u, 1000u, 1013u, 1058u, 99999u}) {
    const std::size_t s = terrain_samples_per_side(n);
    const auto error = [n](std::uint64_t m) {
      return std::llabs(std::int64_t(2 * m * m) - std::int64_t(n));
    };
    for (std::uint64_t m = 1; m < 400; ++m) EXPECT_LE(error(s - 1), error(m)) << n << " " << m;
  }
}

TEST(TerrainGenerator, HeightfieldInTheSlabWithNormalsUp) {
  const auto folder = test_folder("terrain");
  TerrainOptions options;
  options.triangles = 1800;  // s = 31
  options.seed = 9;
  TerrainSummary summary;
  {
    MeshWriter writer(folder / "terrain.ply");
    summary = generate_terrain(options, writer);
    writer.commit();
  }
  EXPECT_EQ(summary.samples_per_side, 31u);
  EXPECT_EQ(summary.source_side, 1201u);
  EXPECT_EQ(summary.fractal_side, 2049u);
  EXPECT_EQ(summary.bands, 1u);

  const TriangleSoup soup = read_mesh(folder / "terrain.ply");
  ASSERT_EQ(soup.triangle_count(), 2u * 30 * 30);
  EXPECT_EQ(soup.vertices.size(), 31u * 31);
  double lowest = 1e300, highest = -1e300;
  std::map<std::pair<double, double>, int> columns;
  for (const auto& v : soup.vertices) {
    EXPECT_GE(v[0], 0.0);
    EXPECT_LE(v[0], 1.0);
    EXPECT_GE(v[1], 0.0);
    EXPECT_LE(v[1], 1.0);
    EXPECT_GE(v[2], options.slab_low);
    EXPECT_LE(v[2], options.slab_high);
    lowest = std::min(lowest, v[2]);
    highest = std::max(highest, v[2]);
    ++columns[{v[0], v[1]}];
  }
  EXPECT_DOUBLE_EQ(lowest, options.slab_low);
  EXPECT_NEAR(highest, options.slab_high, 1e-12);
  EXPECT_EQ(columns.size(), 31u * 31);  // one height per (x, y): a heightfield
  double area = 0.0;
  for (std::size_t t = 0; t < soup.triangle_count(); ++t) {
    const auto [a, b, c] = soup.corners(t);
    const double up = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    ASSERT_GT(up, 0.0) << "triangle " << t;
    area += 0.5 * up;
  }
  EXPECT_NEAR(area, 1.0, 1e-12);  // the projections tile the unit square
}

TEST(TerrainGenerator, LargeTerrainIsWrittenInBandsThatMeetExactly) {
  const auto folder = test_folder("terrain_bands");
  TerrainOptions options;
  options.triangles = 2 * 760 * 760;  // s = 761: more than one band of 2^20 triangles
  options.seed = 10;
  TerrainSummary summary;
  {
    MeshWriter writer(folder / "terrain.ply");
    summary = generate_terrain(options, writer);
    writer.commit();
  }
  const std::size_t s = 761;
  ASSERT_EQ(summary.samples_per_side, s);
  EXPECT_EQ(summary.bands, 2u);
  // The second band repeats the row the first one ends with.
  EXPECT_EQ(summary.vertices, s * s + s);
  const TriangleSoup soup = read_mesh(folder / "terrain.ply");
  ASSERT_EQ(soup.triangle_count(), 2u * 760 * 760);
  EXPECT_EQ(soup.part_names, std::vector<std::string>{"terrain"});  // one surface, one part
  std::map<std::pair<double, double>, double> height;
  for (const auto& v : soup.vertices) {
    const auto [it, inserted] = height.emplace(std::make_pair(v[0], v[1]), v[2]);
    if (!inserted) {
      ASSERT_EQ(it->second, v[2]) << "repeated sample with another height";
    }
  }
  EXPECT_EQ(height.size(), s * s);
  double area = 0.0;
  for (std::size_t t = 0; t < soup.triangle_count(); ++t) {
    const auto [a, b, c] = soup.corners(t);
    const double up = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    ASSERT_GT(up, 0.0) << "triangle " << t;
    area += 0.5 * up;
  }
  EXPECT_NEAR(area, 1.0, 1e-9);
}

TEST(TerrainGenerator, SameSeedSameBytesOtherSeedOtherBytes) {
  const auto folder = test_folder("terrain_determinism");
  const auto write = [&](const std::string& name, std::uint64_t seed) {
    TerrainOptions options;
    options.triangles = 800;
    options.seed = seed;
    MeshWriter writer(folder / name);
    generate_terrain(options, writer);
    writer.commit();
    return file_bytes(folder / name);
  };
  const std::string a = write("a.ply", 4), b = write("b.ply", 4), c = write("c.ply", 5);
  EXPECT_FALSE(a.empty());
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
}

// ---------------------------------------------------------------------------------------------
// Flying objects

void expect_fitted(const TriangleSoup& soup, double size) {
  const BoundingBox box = soup.bounds();
  const Vec3 extent = box.size();
  EXPECT_NEAR(std::max({extent[0], extent[1], extent[2]}), size, 1e-12);
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(box.center()[a], 0.0, 1e-12) << "axis " << a;
    EXPECT_GE(box.lo[a], -0.5 * size - 1e-12);
    EXPECT_LE(box.hi[a], 0.5 * size + 1e-12);
  }
}

TEST(ObjectGenerator, StudySizesFitTheCubeAndAreClosed) {
  const MeshLibrary library = MeshLibrary::load_default();
  for (std::uint64_t n : {4u, 116u, 500u, 2000u}) {
    SCOPED_TRACE("triangles " + std::to_string(n));
    ObjectOptions options;
    options.triangles = n;
    const GeneratedObject object = generate_object(options, &library);
    const double count = double(object.soup.triangle_count());
    EXPECT_LE(std::abs(count - double(n)), 0.05 * double(n) + 2.0) << object.source;
    expect_fitted(object.soup, 0.05);
    EXPECT_TRUE(object.closed) << object.source;
    EXPECT_EQ(object.closed, closed_and_consistent(object.soup.triangles));
    EXPECT_GT(signed_volume6(object.soup.vertices, object.soup.triangles), 0.0) << object.source;
    if (n > sphere_object_limit) {
      EXPECT_GE(object.source_triangles, n) << object.source;
      EXPECT_NE(object.source.find("simplified"), std::string::npos) << object.source;
    }
  }
}

TEST(ObjectGenerator, DeterministicAndTheSeedPicksAmongMeshes) {
  const MeshLibrary library = MeshLibrary::load_default();
  ObjectOptions options;
  options.triangles = 600;
  const GeneratedObject a = generate_object(options, &library);
  const GeneratedObject b = generate_object(options, &library);
  EXPECT_EQ(a.source, b.source);
  EXPECT_EQ(a.soup.vertices, b.soup.vertices);
  EXPECT_EQ(a.soup.triangles, b.soup.triangles);
  // The closest mesh at or above the request.
  std::size_t closest = ~std::size_t{0};
  for (const auto& mesh : library.meshes())
    if (mesh.triangle_count() >= 600) closest = std::min(closest, mesh.triangle_count());
  EXPECT_EQ(a.source_triangles, closest);

  bool other_mesh = false;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    options.seed = seed;
    const GeneratedObject c = generate_object(options, &library);
    const GeneratedObject d = generate_object(options, &library);
    EXPECT_EQ(c.soup.vertices, d.soup.vertices) << "seed " << seed;
    EXPECT_GE(c.source_triangles, 600u);
    other_mesh = other_mesh || c.source_triangles != a.source_triangles;
  }
  EXPECT_TRUE(other_mesh);
}

TEST(ObjectGenerator, SphereResolutionIsCloseToTheRequest) {
  for (std::uint64_t n = 5; n <= sphere_object_limit; ++n) {
    const auto [slices, stacks] = uv_sphere_resolution(n);
    EXPECT_GE(slices, 3u);
    EXPECT_GE(stacks, 2u);
    const double count = double(2 * slices * (stacks - 1));
    EXPECT_LE(std::abs(count - double(n)), std::max(0.1 * double(n), 3.0)) << n;
    ObjectOptions options;
    options.triangles = n;
    const GeneratedObject sphere = generate_object(options);
    EXPECT_EQ(double(sphere.soup.triangle_count()), count);
    EXPECT_TRUE(sphere.closed) << n;
    EXPECT_GT(signed_volume6(sphere.soup.vertices, sphere.soup.triangles), 0.0) << n;
  }
  EXPECT_EQ(uv_sphere_resolution(116), (std::pair<std::size_t, std::size_t>{12, 6}));
}

TEST(ObjectGenerator, SubdividesWhenNoMeshIsLargeEnoughAndPrefersClosedMeshes) {
  // Only a 4-triangle tetrahedron: Loop subdivision up to 1024, then simplified to ~300.
  std::vector<LibraryMesh> tiny;
  tiny.push_back(library_mesh("tetra", tetra_soup()));
  const MeshLibrary tiny_library(std::move(tiny));
  ObjectOptions options;
  options.triangles = 300;
  const GeneratedObject refined = generate_object(options, &tiny_library);
  EXPECT_NE(refined.source.find("subdivided"), std::string::npos) << refined.source;
  EXPECT_LE(std::abs(double(refined.soup.triangle_count()) - 300.0), 17.0);
  EXPECT_TRUE(refined.closed);
  expect_fitted(refined.soup, 0.05);

  // An open mesh closer to the request loses to a closed one.
  TriangleSoup open = box_soup({0, 0, 0}, {1, 1, 1});
  open.triangles.pop_back();
  open.part_of.pop_back();
  std::vector<LibraryMesh> meshes;
  meshes.push_back(library_mesh("open", open));
  meshes.push_back(library_mesh("closed", octahedron_soup()));
  const MeshLibrary mixed(std::move(meshes));
  options.triangles = 201;  // both need subdividing; "open" (11) ranks before "closed" (8)
  const GeneratedObject chosen = generate_object(options, &mixed);
  EXPECT_EQ(chosen.soup.part_names.at(0), "closed");
  EXPECT_TRUE(chosen.closed);

  EXPECT_THROW(generate_object(options), InputError);  // needs a library
  options.triangles = 0;
  EXPECT_THROW(generate_object(options), InputError);
}

}  // namespace
}  // namespace tetrapage
