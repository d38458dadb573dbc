#include "tetrapage/formats/SurfaceComponents.h"

#include <bit>
#include <numeric>
#include <unordered_map>

#include "tetrapage/formats/EdgeParity.h"

namespace tetrapage {
namespace {

// A vertex position within a part, bit for bit (-0.0 read as 0.0).
struct PositionKey {
  std::uint32_t part;
  std::array<std::uint64_t, 3> bits;
  bool operator==(const PositionKey&) const = default;
};

struct PositionKeyHash {
  std::size_t operator()(const PositionKey& key) const {
    std::uint64_t h = 0x9e3779b97f4a7c15ULL * (key.part + 1);
    for (const std::uint64_t w : key.bits) {
      h ^= w + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2);
      h *= 0xbf58476d1ce4e5b9ULL;
    }
    return std::size_t(h ^ (h >> 31));
  }
};

PositionKey key_of(std::uint32_t part, const Vec3& p) {
  PositionKey key{part, {}};
  for (int a = 0; a < 3; ++a) key.bits[a] = std::bit_cast<std::uint64_t>(p[a] == 0.0 ? 0.0 : p[a]);
  return key;
}

class UnionFind {
 public:
  std::uint32_t add() {
    parent_.push_back(std::uint32_t(parent_.size()));
    return parent_.back();
  }
  std::uint32_t find(std::uint32_t x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    a = find(a), b = find(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  }

 private:
  std::vector<std::uint32_t> parent_;
};

// Per triangle corner, the node of its position within the triangle's part. Most soups index
// shared vertices, so a vertex index keeps the node it was last given (for its part).
std::vector<std::array<std::uint32_t, 3>> corner_nodes(const TriangleSoup& soup, UnionFind& sets) {
  std::unordered_map<PositionKey, std::uint32_t, PositionKeyHash> node_of_position;
  node_of_position.reserve(soup.vertices.size());
  constexpr std::uint32_t kNone = 0xffffffffu;
  std::vector<std::uint32_t> node_of_vertex(soup.vertices.size(), kNone), part_of_vertex(soup.vertices.size(), kNone);
  std::vector<std::array<std::uint32_t, 3>> nodes(soup.triangle_count());
  for (std::size_t t = 0; t < soup.triangle_count(); ++t) {
    const std::uint32_t part = soup.part_of.empty() ? 0 : soup.part_of[t];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = soup.triangles[t][k];
      if (part_of_vertex[v] != part) {
        const auto [it, added] = node_of_position.try_emplace(key_of(part, soup.vertices[v]), 0);
        if (added) it->second = sets.add();
        node_of_vertex[v] = it->second;
        part_of_vertex[v] = part;
      }
      nodes[t][k] = node_of_vertex[v];
    }
  }
  return nodes;
}

}  // namespace

std::size_t SurfaceComponents::closed_count() const {
  std::size_t closed = 0;
  for (const SurfaceComponent& c : components) closed += c.closed;
  return closed;
}

SurfaceComponents find_surface_components(const TriangleSoup& soup) {
  UnionFind sets;
  const auto nodes = corner_nodes(soup, sets);
  for (const auto& n : nodes) sets.unite(n[0], n[1]), sets.unite(n[0], n[2]);

  SurfaceComponents result;
  result.component_of.resize(soup.triangle_count());
  constexpr std::uint32_t kNone = 0xffffffffu;
  std::vector<std::uint32_t> component_of_root;
  std::vector<EdgeParity> parity;
  for (std::size_t t = 0; t < soup.triangle_count(); ++t) {
    const std::uint32_t root = sets.find(nodes[t][0]);
    if (root >= component_of_root.size()) component_of_root.resize(root + 1, kNone);
    std::uint32_t& c = component_of_root[root];
    const auto corners = soup.corners(t);
    if (c == kNone) {
      c = std::uint32_t(result.components.size());
      SurfaceComponent component;
      component.part = soup.part_of.empty() ? 0 : soup.part_of[t];
      component.vertex = corners[0];
      component.first_triangle = t;
      result.components.push_back(component);
      parity.emplace_back();
    }
    result.component_of[t] = c;
    SurfaceComponent& component = result.components[c];
    ++component.triangles;
    for (const Vec3& p : corners) component.bounds.extend(p);
    parity[c].add_triangle(corners);
  }
  for (std::size_t c = 0; c < parity.size(); ++c) result.components[c].closed = parity[c].closed();
  return result;
}

}  // namespace tetrapage
