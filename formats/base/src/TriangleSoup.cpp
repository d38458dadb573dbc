#include "tetrapage/formats/base/TriangleSoup.h"

namespace tetrapage {

std::uint32_t TriangleSoup::add_part(std::string name, std::string path) {
  // Paths are stored from the first that differs from its name on (an empty path is the
  // name); the first part may be that one, when there are no names to copy yet.
  const bool paths = !part_paths.empty() || !path.empty();
  if (paths && part_paths.empty()) part_paths = part_names;
  if (paths) part_paths.push_back(path.empty() ? name : std::move(path));
  part_names.push_back(std::move(name));
  return static_cast<std::uint32_t>(part_names.size() - 1);
}

void TriangleSoup::append(const TriangleSoup& other) {
  const auto vertex_offset = static_cast<std::uint32_t>(vertices.size());
  const auto part_offset = static_cast<std::uint32_t>(part_names.size());
  vertices.insert(vertices.end(), other.vertices.begin(), other.vertices.end());
  triangles.reserve(triangles.size() + other.triangles.size());
  for (const auto& t : other.triangles)
    triangles.push_back({t[0] + vertex_offset, t[1] + vertex_offset, t[2] + vertex_offset});
  for (auto p : other.part_of) part_of.push_back(p + part_offset);
  const bool paths = !part_paths.empty() || !other.part_paths.empty();
  if (paths && part_paths.empty()) part_paths = part_names;
  if (paths)
    for (std::size_t p = 0; p < other.part_count(); ++p) part_paths.push_back(other.part_path(p));
  part_names.insert(part_names.end(), other.part_names.begin(), other.part_names.end());
}

}  // namespace tetrapage
