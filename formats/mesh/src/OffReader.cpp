// OFF (Geomview): the keyword ([ST][C][N]OFF), then `nv nf [ne]` (on the keyword's line or
// the next), nv vertex lines and nf face lines `n i1 ... in [colour]`. '#' starts a comment.
// Read line by line because a face's optional colour values are only delimited by the line.

#include <vector>

#include "ReaderSupport.h"

namespace tetrapage::detail {
namespace {

/// The next line with data: comment stripped, leading blanks skipped, blank lines skipped.
bool next_data_line(InputFile& file, std::string_view& line) {
  while (file.next_line(line)) {
    const std::size_t hash = line.find('#');
    if (hash != std::string_view::npos) line = line.substr(0, hash);
    skip_spaces(line);
    if (!line.empty()) return true;
  }
  return false;
}

/// OFF, COFF, NOFF, CNOFF, STOFF, STCOFF, ...: the prefixes only add values after x y z on
/// vertex lines, which are ignored. 4OFF (4D) and nOFF (any dimension) change the layout.
bool is_off_keyword(std::string_view keyword) {
  if (!keyword.ends_with("OFF")) return false;
  keyword.remove_suffix(3);
  if (keyword.starts_with("ST")) keyword.remove_prefix(2);
  if (keyword.starts_with("C")) keyword.remove_prefix(1);
  if (keyword.starts_with("N")) keyword.remove_prefix(1);
  return keyword.empty();
}

/// The counts must fit in what follows, before they size anything: every vertex and face
/// takes a line of at least 2 bytes (a token and its newline; the last line needs none).
void check_counts_fit(const InputFile& file, std::uint64_t vertex_count, std::uint64_t face_count) {
  constexpr std::uint64_t line_bytes = 2;
  const std::uint64_t lines = file.bytes_left() / line_bytes + 1;
  const bool fits = vertex_count <= lines && face_count <= lines - vertex_count;
  if (!fits)
    throw FormatError(where_line(file) + "the header announces " + std::to_string(vertex_count) +
                      " vertices and " + std::to_string(face_count) + " faces, more than the " +
                      std::to_string(file.bytes_left()) + " bytes after it can hold");
}

}  // namespace

MeshCounts read_off_counts(InputFile& file) {
  std::string_view line;
  if (!next_data_line(file, line)) throw FormatError(file.name() + ": empty file, expected 'OFF'");
  const std::string_view keyword = next_token(line);
  if (!is_off_keyword(keyword)) {
    throw FormatError(
        where_line(file) + "not an OFF file: expected 'OFF', got " + quote_token(keyword) +
        (keyword.ends_with("OFF") ? " (4D and n-dimensional OFF are not supported)" : ""));
  }
  skip_spaces(line);
  if (line.starts_with("BINARY")) {
    throw FormatError(where_line(file) + "binary OFF is not supported");
  }
  if (line.empty() && !next_data_line(file, line)) {
    throw FormatError(file.name() + ": the file ends before the vertex and face counts");
  }
  MeshCounts counts;
  std::uint64_t& vertex_count = counts.vertices;
  std::uint64_t& face_count = counts.faces;
  {
    const std::string_view vertices_token = next_token(line);
    const std::string_view faces_token = next_token(line);
    if (!parse_unsigned(vertices_token, vertex_count) || !parse_unsigned(faces_token, face_count)) {
      throw FormatError(where_line(file) + "expected the counts 'vertices faces [edges]', got " +
                        quote_token(std::string(vertices_token) + " " + std::string(faces_token)));
    }
  }
  check_counts_fit(file, vertex_count, face_count);
  if (vertex_count > max_vertices) {
    throw InputError(where_line(file) + std::to_string(vertex_count) +
                     " vertices are more than a soup can index");
  }
  counts.triangles = face_count;
  return counts;
}

TriangleSoup read_off(InputFile& file, ReadReport& report, const SoupChunks* chunks) {
  report.encoding = "ascii";
  const MeshCounts counts = read_off_counts(file);
  const std::uint64_t vertex_count = counts.vertices, face_count = counts.faces;
  std::string_view line;
  SoupBuilder soup(file.name(), report, chunks);
  soup.begin_part(file.path().stem().string());
  soup.reserve(vertex_count, face_count, file.size());
  for (std::uint64_t v = 0; v < vertex_count; ++v) {
    if (!next_data_line(file, line)) {
      throw FormatError(file.name() + ": the file ends after " + std::to_string(v) + " of " +
                        std::to_string(vertex_count) + " vertices");
    }
    Vec3 p{};
    for (double& coordinate : p) {
      const std::string_view token = next_token(line);
      if (!parse_double(token, coordinate)) {
        throw FormatError(where_line(file) + "vertex " + std::to_string(v) +
                          " needs three numbers, got " +
                          (token.empty() ? std::string("fewer") : quote_token(token)));
      }
    }
    if (!is_finite(p)) throw_not_finite(where_line(file) + "vertex " + std::to_string(v) + ": ", p);
    soup.add_vertex(p);
  }
  std::vector<std::uint32_t> corners;
  for (std::uint64_t f = 0; f < face_count; ++f) {
    if (!next_data_line(file, line)) {
      throw FormatError(file.name() + ": the file ends after " + std::to_string(f) + " of " +
                        std::to_string(face_count) + " faces");
    }
    const std::string_view count_token = next_token(line);
    std::uint64_t count = 0;
    if (!parse_unsigned(count_token, count)) {
      throw FormatError(where_line(file) + "face " + std::to_string(f) +
                        ": expected a corner count, got " + quote_token(count_token));
    }
    if (count < 3) {
      throw FormatError(where_line(file) + "face " + std::to_string(f) + " has " +
                        std::to_string(count) + " corners, a face needs at least 3");
    }
    corners.clear();
    for (std::uint64_t k = 0; k < count; ++k) {
      const std::string_view token = next_token(line);
      std::int64_t index = 0;
      if (!parse_integer(token, index)) {
        throw FormatError(where_line(file) + "face " + std::to_string(f) + ": expected " +
                          std::to_string(count) + " vertex indices, got " +
                          (token.empty() ? std::string("fewer") : quote_token(token)));
      }
      if (index < 0 || static_cast<std::uint64_t>(index) >= vertex_count) {
        throw InputError(where_line(file) + "face " + std::to_string(f) + ": vertex index " +
                         std::to_string(index) + " out of range (" + std::to_string(vertex_count) +
                         " vertices)");
      }
      corners.push_back(static_cast<std::uint32_t>(index));
    }
    // Whatever follows on the line is the face's colour.
    soup.add_polygon(corners);
  }
  return soup.finish();
}

}  // namespace tetrapage::detail
