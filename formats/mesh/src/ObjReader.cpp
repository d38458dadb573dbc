// Wavefront OBJ: `v x y z [w]` and `f` lines (i, i/t, i//n, i/t/n; negative indices count
// back from the last vertex defined), and `o` and `g` lines, which make parts (the rule is in
// MeshReader.h). Everything else (vt, vn, vp, s, usemtl, mtllib, l, p, comments) carries
// nothing a collision model needs and is skipped.

#include <map>
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

// The part the next face goes to: `o` and `g` change the (object, group) in force, and its
// part is looked up (or made) only at a face, so that names without faces make no part.
class ObjParts {
 public:
  ObjParts(SoupBuilder& soup, std::string stem) : soup_(soup), stem_(std::move(stem)) {}

  void object(std::string_view name) {
    object_ = name;
    group_.clear();
    chosen_ = false;
  }
  void group(std::string_view name) {
    group_ = name;
    chosen_ = false;
  }
  void before_face() {
    if (chosen_) return;
    const auto [it, made] = parts_.try_emplace({object_, group_}, 0);
    if (made) it->second = begin_part();
    soup_.resume_part(it->second);
    chosen_ = true;
  }

 private:
  std::uint32_t begin_part() {
    if (group_.empty()) return soup_.begin_part(object_.empty() ? stem_ : object_);
    if (object_.empty()) return soup_.begin_part(group_);
    return soup_.begin_part(group_, object_ + "/" + group_);
  }

  SoupBuilder& soup_;
  std::string stem_, object_, group_;
  std::map<std::pair<std::string, std::string>, std::uint32_t> parts_;
  bool chosen_ = false;  ///< the part in force is set (until the next `o` or `g`)
};

// The rest of an `o` or `g` line, trimmed.
std::string_view part_name(std::string_view rest) {
  skip_spaces(rest);
  while (!rest.empty() && is_space(rest.back())) rest.remove_suffix(1);
  return rest;
}

}  // namespace

TriangleSoup read_obj(InputFile& file, ReadReport& report, const SoupChunks* chunks) {
  report.encoding = "ascii";
  SoupBuilder soup(file.name(), report, chunks);
  ObjParts parts(soup, file.path().stem().string());
  std::vector<std::uint32_t> corners;
  std::string_view line;
  while (file.next_line(line)) {
    if (file.line_number() == 1 && line.starts_with("\xEF\xBB\xBF")) line.remove_prefix(3);
    skip_spaces(line);
    if (line.empty() || (line.size() > 1 && !is_space(line[1]))) continue;
    if (line[0] == 'o' || line[0] == 'g') {
      const std::string_view name = part_name(line.substr(1));
      line[0] == 'o' ? parts.object(name) : parts.group(name);
      continue;
    }
    if (line.size() < 2) continue;
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
      parts.before_face();
      soup.add_polygon(corners);
    }
  }
  return soup.finish();
}

}  // namespace tetrapage::detail
