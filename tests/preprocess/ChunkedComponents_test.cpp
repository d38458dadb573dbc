// ChunkedComponents: the components of a soup handed over in chunks, against an oracle of the
// test's own that holds the whole soup (triangles united through std::map of exact positions,
// closed when every edge is used an even number of times, counted in a map), on CGAL's meshes:
// closed and open, copies in other parts at the same positions (apart), copies in the same part
// sharing positions (one), and corners not shared between triangles (as an STL stores them).

#include "tetrapage/preprocess/ChunkedComponents.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <map>
#include <numeric>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/MeshReader.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;

struct Expected {
  std::vector<std::uint32_t> component_of;  // per triangle
  std::vector<SurfaceComponent> components;
};

Expected oracle(const TriangleSoup& soup) {
  using Position = std::tuple<double, double, double>;
  const auto position = [&](std::uint32_t v) {
    const Vec3& p = soup.vertices[v];
    return Position{p[0] + 0.0, p[1] + 0.0, p[2] + 0.0};  // -0.0 + 0.0 is +0.0
  };
  std::vector<std::size_t> parent(soup.triangle_count());
  std::iota(parent.begin(), parent.end(), 0);
  const std::function<std::size_t(std::size_t)> root = [&](std::size_t t) {
    return parent[t] == t ? t : parent[t] = root(parent[t]);
  };
  std::map<std::pair<std::uint32_t, Position>, std::size_t> first_user;
  for (std::size_t t = 0; t < soup.triangle_count(); ++t)
    for (const std::uint32_t v : soup.triangles[t]) {
      const auto [it, made] = first_user.insert({{soup.part_of[t], position(v)}, t});
      if (!made) {
        const std::size_t a = root(it->second), b = root(t);
        parent[std::max(a, b)] = std::min(a, b);
      }
    }
  Expected expected;
  std::map<std::size_t, std::uint32_t> number;
  std::vector<std::map<std::pair<Position, Position>, int>> edges;
  for (std::size_t t = 0; t < soup.triangle_count(); ++t) {
    const auto [it, made] = number.insert({root(t), std::uint32_t(expected.components.size())});
    const auto corners = soup.corners(t);
    if (made) {
      SurfaceComponent c;
      c.part = soup.part_of[t];
      c.first_triangle = t;
      c.vertex = corners[0];
      expected.components.push_back(c);
      edges.emplace_back();
    }
    SurfaceComponent& c = expected.components[it->second];
    ++c.triangles;
    for (const Vec3& p : corners) c.bounds.extend(p);
    for (int k = 0; k < 3; ++k) {
      const Position a = position(soup.triangles[t][k]), b = position(soup.triangles[t][(k + 1) % 3]);
      ++edges[it->second][std::minmax(a, b)];
    }
    expected.component_of.push_back(it->second);
  }
  for (std::size_t c = 0; c < edges.size(); ++c) {
    expected.components[c].closed = true;
    for (const auto& [edge, uses] : edges[c]) expected.components[c].closed &= uses % 2 == 0;
  }
  return expected;
}

// Appends `mesh` to `soup` in `part`, moved by `shift`; unshared: each triangle its own corners.
void append(TriangleSoup& soup, const TriangleSoup& mesh, std::uint32_t part, double shift,
            bool unshared) {
  const auto base = std::uint32_t(soup.vertices.size());
  if (!unshared)
    for (const Vec3& p : mesh.vertices) soup.vertices.push_back({p[0] + shift, p[1], p[2]});
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    if (unshared) {
      const auto first = std::uint32_t(soup.vertices.size());
      for (const Vec3& p : mesh.corners(t)) soup.vertices.push_back({p[0] + shift, p[1], p[2]});
      soup.triangles.push_back({first, first + 1, first + 2});
    } else {
      const auto& c = mesh.triangles[t];
      soup.triangles.push_back({base + c[0], base + c[1], base + c[2]});
    }
    soup.part_of.push_back(part);
  }
}

// Triangles [first, end) of `soup` as a chunk with its own vertices.
TriangleSoup chunk_of(const TriangleSoup& soup, std::size_t first, std::size_t end) {
  TriangleSoup chunk;
  std::map<std::uint32_t, std::uint32_t> local;
  for (std::size_t t = first; t < end; ++t) {
    TriangleIndices c{};
    for (int k = 0; k < 3; ++k) {
      const auto [it, made] = local.insert({soup.triangles[t][k], std::uint32_t(chunk.vertices.size())});
      if (made) chunk.vertices.push_back(soup.vertices[soup.triangles[t][k]]);
      c[k] = it->second;
    }
    chunk.triangles.push_back(c);
    chunk.part_of.push_back(soup.part_of[t]);
  }
  return chunk;
}

TEST(ChunkedComponents, ChunksUniteIntoTheWholeSoupsComponents) {
  const fs::path folder = fs::path(TETRAPAGE_TEST_TMP) / ("chunked-" + std::to_string(::getpid()));
  fs::create_directories(folder);
  TriangleSoup soup;
  int meshes = 0;
  for (const char* name : {"cube-shuffled.off", "mech-holes-shark.off", "knot1.off"}) {
    const fs::path path = fs::path(TETRAPAGE_MESH_DIR) / name;
    if (!fs::exists(path)) continue;
    const TriangleSoup mesh = read_mesh(path);
    append(soup, mesh, 0, 0, false);
    append(soup, mesh, 1, 0, false);  // the same positions in another part: apart
    append(soup, mesh, 0, 0, true);   // the same positions and part, corners unshared: joined
    append(soup, mesh, 2, 1e3, true);
    ++meshes;
  }
  ASSERT_GT(meshes, 0) << "no real mesh found under " << TETRAPAGE_MESH_DIR;
  soup.vertices.push_back({-0.0, 0.0, 0.0});  // -0.0 and 0.0 are one position
  soup.vertices.push_back({0.0, 1.0, 0.0});
  soup.vertices.push_back({0.0, 0.0, 1.0});
  soup.vertices.push_back({0.0, -1.0, 0.0});
  const auto v = std::uint32_t(soup.vertices.size());
  soup.triangles.push_back({v - 4, v - 3, v - 2});
  soup.part_of.push_back(3);
  soup.vertices.push_back({0.0, 0.0, 0.0});
  soup.triangles.push_back({v, v - 2, v - 1});
  soup.part_of.push_back(3);
  const Expected expected = oracle(soup);
  ASSERT_GT(expected.components.size(), 4u);

  // Chunks of one triangle in one ample bucket; chunks of a few in one bucket where many were
  // needed (split, up to three times); larger chunks in buckets as the positions need them.
  struct Run {
    std::size_t size;
    std::uint64_t positions, bytes;
  };
  for (const Run run : {Run{1, 1, std::uint64_t(1) << 24}, Run{7, 1, 1 << 16},
                        Run{997, soup.vertices.size(), 1 << 16}}) {
    const std::size_t size = run.size;
    {
      SCOPED_TRACE("chunks of " + std::to_string(size) + ", " + std::to_string(run.positions) +
                   " positions expected in buckets of " + std::to_string(run.bytes));
      ChunkedComponents chunked(folder, "test", run.positions, run.bytes);
      std::vector<std::uint32_t> label_of;
      for (std::size_t first = 0; first < soup.triangle_count(); first += size) {
        TriangleSoup chunk = chunk_of(soup, first, std::min(first + size, soup.triangle_count()));
        chunked.add_chunk(chunk, first);
        label_of.insert(label_of.end(), chunk.part_of.begin(), chunk.part_of.end());
      }
      const ChunkedComponents::United united = chunked.unite(~std::uint64_t(0), "");
      ASSERT_EQ(united.components.size(), expected.components.size());
      for (std::size_t t = 0; t < soup.triangle_count(); ++t)
        ASSERT_EQ(united.component_of_label[label_of[t]], expected.component_of[t]) << "triangle " << t;
      for (std::size_t c = 0; c < expected.components.size(); ++c) {
        const SurfaceComponent &a = united.components[c], &b = expected.components[c];
        EXPECT_EQ(a.part, b.part) << c;
        EXPECT_EQ(a.closed, b.closed) << c;
        EXPECT_EQ(a.triangles, b.triangles) << c;
        EXPECT_EQ(a.first_triangle, b.first_triangle) << c;
        EXPECT_EQ(a.vertex, b.vertex) << c;
        EXPECT_EQ(a.bounds.lo, b.bounds.lo) << c;
        EXPECT_EQ(a.bounds.hi, b.bounds.hi) << c;
      }
    }
  }
  // More components than allowed: refused with the caller's words.
  {
    ChunkedComponents chunked(folder, "limit", soup.vertices.size(), 1 << 16);
    TriangleSoup chunk = chunk_of(soup, 0, soup.triangle_count());
    chunked.add_chunk(chunk, 0);
    try {
      chunked.unite(expected.components.size() - 1, "too many");
      ADD_FAILURE() << "not refused";
    } catch (const InputError& error) {
      EXPECT_STREQ(error.what(), "too many");
    }
  }
  for (const auto& entry : fs::directory_iterator(folder))
    ADD_FAILURE() << "left behind: " << entry.path();
  fs::remove_all(folder);
}

}  // namespace
}  // namespace tetrapage
