#include "tetrapage/formats/TriangleSoup.h"

namespace tetrapage {

void TriangleSoup::append(const TriangleSoup& other) {
  const auto vertex_offset = static_cast<std::uint32_t>(vertices.size());
  const auto part_offset = static_cast<std::uint32_t>(part_names.size());
  vertices.insert(vertices.end(), other.vertices.begin(), other.vertices.end());
  triangles.reserve(triangles.size() + other.triangles.size());
  for (const auto& t : other.triangles)
    triangles.push_back({t[0] + vertex_offset, t[1] + vertex_offset, t[2] + vertex_offset});
  for (auto p : other.part_of) part_of.push_back(p + part_offset);
  part_names.insert(part_names.end(), other.part_names.begin(), other.part_names.end());
}

}  // namespace tetrapage
