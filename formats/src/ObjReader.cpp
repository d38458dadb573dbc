// Wavefront OBJ: `v x y z [w]` and `f` lines (i, i/t, i//n, i/t/n; negative indices count
// back from the last vertex defined). Everything else (vt, vn, vp, g, o, s, usemtl, mtllib,
// l, p, comments) carries nothing a collision model needs and is skipped.

#include <vector>

#include "ReaderSupport.h"

namespace tetrapage::detail {
namespace {

std::uint32_t parse_face_corner(const InputFile& file, std::string_view token,
                                std::uint64_t vertex_count) {
  const std::string_view index_text = token.substr(0, token.find('/'));
  std::int64_t index = 0;
  if (!parse_integer(index_text, index)) {
    throw FormatError(where_line(file) + "bad face corner " + quote_token(token) +
                      " (expected a vertex index)");
  }
  // 1-based; negative indices are relative to the vertices defined so far.
  const std::int64_t count = static_cast<std::int64_t>(vertex_count);
  const std::int64_t resolved = index > 0 ? index - 1 : count + index;
  if (index == 0 || resolved < 0 || resolved >= count) {
    throw InputError(where_line(file) + "vertex index " + std::to_string(index) +
                     " out of range (" + std::to_string(vertex_count) +
                     " vertices defined so far)");
  }
  return static_cast<std::uint32_t>(resolved);
}

}  // namespace

TriangleSoup read_obj(InputFile& file, ReadReport& report) {
  report.encoding = "ascii";
  SoupBuilder soup(file.name(), report);
  soup.begin_part(file.path().stem().string());
  std::vector<std::uint32_t> corners;
  std::string_view line;
  while (file.next_line(line)) {
    if (file.line_number() == 1 && line.starts_with("\xEF\xBB\xBF")) line.remove_prefix(3);
    skip_spaces(line);
    if (line.size() < 2 || !is_space(line[1])) continue;
    if (line[0] == 'v') {
      line.remove_prefix(2);
      Vec3 p{};
      for (double& coordinate : p) {
        const std::string_view token = next_token(line);
        if (!parse_double(token, coordinate)) {
          throw FormatError(where_line(file) + "vertex needs three numbers, got " +
                            (token.empty() ? std::string("fewer") : quote_token(token)));
        }
      }
      if (!is_finite(p)) throw_not_finite(where_line(file), p);
      if (soup.vertex_count() >= max_vertices) {
        throw InputError(where_line(file) + "more than " + std::to_string(max_vertices) +
                         " vertices");
      }
      soup.add_vertex(p);
    } else if (line[0] == 'f') {
      line.remove_prefix(2);
      corners.clear();
      for (std::string_view token = next_token(line); !token.empty(); token = next_token(line))
        corners.push_back(parse_face_corner(file, token, soup.vertex_count()));
      if (corners.size() < 3) {
        throw FormatError(where_line(file) + "face has " + std::to_string(corners.size()) +
                          " corners, a face needs at least 3");
      }
      soup.add_polygon(corners);
    }
  }
  return soup.finish();
}

}  // namespace tetrapage::detail
