#include "tetrapage/formats/mesh/SurfaceComponents.h"

#include <algorithm>
#include <numeric>

#include "tetrapage/formats/mesh/EdgeParity.h"
#include "tetrapage/formats/mesh/PositionBits.h"
#include "tetrapage/formats/mesh/UnionFind.h"

namespace tetrapage {
namespace {

// The distinct positions a soup is expected to hold: about one per vertex entry in an indexed
// soup, about one per six in a soup whose triangles share no entries (an STL).
std::uint64_t expected_positions(std::uint64_t vertices, std::uint64_t triangles) {
  return vertices <= 2 * triangles ? vertices : vertices / 6;
}

// The hash table's first size for `expected` positions: at most half full.
std::uint64_t initial_slots(std::uint64_t expected) {
  std::uint64_t slots = 1 << 12;
  while (slots < 2 * expected) slots *= 2;
  return slots;
}

// The distinct (part, position) pairs of a soup's corners, each a node of the union-find.
// Open addressing over a power-of-two table at most half full, keyed by a vertex that holds the
// position (no allocation per vertex: a node-based map tripled the ingest of a 10M file).
class PositionNodes {
 public:
  // Sized for the distinct positions expected: about one per vertex entry in an indexed soup,
  // about one per six in a soup whose triangles share no entries (an STL); it doubles beyond.
  explicit PositionNodes(const TriangleSoup& soup) : soup_(soup) {
    const std::uint64_t expected = expected_positions(soup.vertices.size(), soup.triangle_count());
    slots_.assign(std::size_t(initial_slots(expected)), kEmpty);
    node_of_vertex_.assign(soup.vertices.size(), kEmpty);
    part_of_vertex_.assign(soup.vertices.size(), kEmpty);
  }
  // The node of vertex v in `part`, made on first sight.
  std::uint32_t node(std::uint32_t v, std::uint32_t part, UnionFind& sets) {
    if (part_of_vertex_[v] == part) return node_of_vertex_[v];  // indexed soups share vertices
    const Vec3& p = soup_.vertices[v];
    const std::array<std::uint64_t, 3> key{coordinate_bits(p[0]), coordinate_bits(p[1]), coordinate_bits(p[2])};
    std::uint32_t found = kEmpty;
    for (std::size_t slot = hash(key, part) & (slots_.size() - 1);; slot = (slot + 1) & (slots_.size() - 1)) {
      const std::uint32_t entry = slots_[slot];
      if (entry == kEmpty) {
        slots_[slot] = std::uint32_t(entries_.size());
        found = sets.add();
        entries_.push_back({v, part, found});
        if (2 * entries_.size() > slots_.size()) grow();
        break;
      }
      const Entry& e = entries_[entry];
      const Vec3& q = soup_.vertices[e.vertex];
      if (e.part == part && coordinate_bits(q[0]) == key[0] && coordinate_bits(q[1]) == key[1] && coordinate_bits(q[2]) == key[2]) {
        found = e.node;
        break;
      }
    }
    node_of_vertex_[v] = found;
    part_of_vertex_[v] = part;
    return found;
  }
  std::size_t count() const { return entries_.size(); }

 private:
  static constexpr std::uint32_t kEmpty = 0xffffffffu;
  struct Entry {
    std::uint32_t vertex, part, node;
  };
  static std::uint64_t hash(const std::array<std::uint64_t, 3>& key, std::uint32_t part) {
    return mix_bits(mix_bits(mix_bits(key[0] ^ part) + key[1]) + key[2]);
  }
  void grow() {
    std::vector<std::uint32_t> slots(2 * slots_.size(), kEmpty);
    for (std::uint32_t i = 0; i < entries_.size(); ++i) {
      const Vec3& q = soup_.vertices[entries_[i].vertex];
      std::size_t slot = hash({coordinate_bits(q[0]), coordinate_bits(q[1]), coordinate_bits(q[2])}, entries_[i].part) & (slots.size() - 1);
      while (slots[slot] != kEmpty) slot = (slot + 1) & (slots.size() - 1);
      slots[slot] = i;
    }
    slots_ = std::move(slots);
  }

  const TriangleSoup& soup_;
  std::vector<std::uint32_t> slots_;  ///< entry numbers
  std::vector<Entry> entries_;        ///< node i is entries_[i] (nodes are added in order)
  std::vector<std::uint32_t> node_of_vertex_, part_of_vertex_;
};

}  // namespace

std::size_t SurfaceComponents::closed_count() const {
  std::size_t closed = 0;
  for (const SurfaceComponent& c : components) closed += c.closed;
  return closed;
}

SurfaceComponents find_surface_components(const TriangleSoup& soup) {
  const auto part_of = [&](std::size_t t) { return soup.part_of.empty() ? 0u : soup.part_of[t]; };
  UnionFind sets;
  PositionNodes nodes(soup);
  for (std::size_t t = 0; t < soup.triangle_count(); ++t) {
    const auto& c = soup.triangles[t];
    const std::uint32_t a = nodes.node(c[0], part_of(t), sets);
    sets.unite(a, nodes.node(c[1], part_of(t), sets));
    sets.unite(a, nodes.node(c[2], part_of(t), sets));
  }
  // Each node's position hashed once (a vertex is shared by about six triangles).
  std::vector<EdgeParity::VertexHash> hashes(nodes.count());
  std::vector<std::uint8_t> hashed(nodes.count(), 0);

  SurfaceComponents result;
  result.component_of.resize(soup.triangle_count());
  constexpr std::uint32_t kNone = 0xffffffffu;
  std::vector<std::uint32_t> component_of_root(nodes.count(), kNone);
  std::vector<EdgeParity>& parity = result.parities;
  for (std::size_t t = 0; t < soup.triangle_count(); ++t) {
    const auto& c = soup.triangles[t];
    std::array<std::uint32_t, 3> node{};
    for (int k = 0; k < 3; ++k) {
      node[k] = nodes.node(c[k], part_of(t), sets);
      if (!hashed[node[k]]) hashes[node[k]] = EdgeParity::hash_vertex(soup.vertices[c[k]]), hashed[node[k]] = 1;
    }
    std::uint32_t& id = component_of_root[sets.find(node[0])];
    const auto corners = soup.corners(t);
    if (id == kNone) {
      id = std::uint32_t(result.components.size());
      SurfaceComponent component;
      component.part = part_of(t);
      component.vertex = corners[0];
      component.first_triangle = t;
      result.components.push_back(component);
      parity.emplace_back();
    }
    result.component_of[t] = id;
    SurfaceComponent& component = result.components[id];
    ++component.triangles;
    for (const Vec3& p : corners) component.bounds.extend(p);
    parity[id].add_hashed_triangle(hashes[node[0]], hashes[node[1]], hashes[node[2]]);
  }
  for (std::size_t c = 0; c < parity.size(); ++c) result.components[c].closed = parity[c].closed();
  return result;
}

std::uint64_t surface_components_bytes(std::uint64_t vertices, std::uint64_t triangles) {
  // As PositionNodes sizes itself.
  const std::uint64_t nodes = expected_positions(vertices, triangles);
  const std::uint64_t slots = initial_slots(nodes);
  const std::uint64_t components = triangles / 64 + 1;
  // The union: slots (old and new while growing), node and part per vertex, entries (12 B)
  // and parents (4 B) at twice their size while growing.
  const std::uint64_t uniting = 6 * slots + 8 * vertices + 32 * nodes;
  // The labelling: the same tables settled, a hash (16 B), a flag and a root (4 B) per node,
  // a component per triangle, and the components with their parities, twice while growing.
  const std::uint64_t labelling = 4 * slots + 8 * vertices + 16 * nodes + 21 * nodes +
                                  4 * triangles +
                                  2 * components * (sizeof(SurfaceComponent) + sizeof(EdgeParity));
  return std::max(uniting, labelling);
}

}  // namespace tetrapage
