// STL, binary and ASCII. A binary file is recognised by its size (84 + 50 * count); ASCII
// files start with "solid". Binary STL stores floats by definition. Corners are not merged:
// every facet brings its own three vertices.

#include <algorithm>
#include <optional>
#include <vector>

#include "ReaderSupport.h"

namespace tetrapage::detail {
namespace {

constexpr std::uint64_t header_bytes = 84;
constexpr std::uint64_t facet_bytes = 50;

TriangleSoup read_binary_stl(InputFile& file, ReadReport& report, std::uint64_t count,
                             const SoupChunks* chunks) {
  report.encoding = "binary";
  if (3 * count > max_vertices) {
    throw InputError(file.name() + ": " + std::to_string(count) +
                     " triangles are more than a soup can index");
  }
  SoupBuilder soup(file.name(), report, chunks);
  soup.vertices_unshared();
  soup.begin_part(file.path().stem().string());
  soup.reserve(3 * count, count, file.size());
  file.take(header_bytes);
  for (std::uint64_t facet = 0; facet < count; ++facet) {
    const auto record = file.take(facet_bytes);
    if (record.size() < facet_bytes) {
      // Only when the file shrank while we read it: the size was checked up front.
      throw FormatError(where_element(file, "triangle", facet) + "truncated: expected " +
                        std::to_string(header_bytes + facet_bytes * count) + " bytes, got " +
                        std::to_string(file.offset()));
    }
    const auto first = static_cast<std::uint32_t>(soup.vertex_count());
    for (int corner = 0; corner < 3; ++corner) {
      const char* xyz = record.data() + 12 + 12 * corner;  // after the normal
      const Vec3 p{load_scalar<float>(xyz, false), load_scalar<float>(xyz + 4, false),
                   load_scalar<float>(xyz + 8, false)};
      if (!is_finite(p)) throw_not_finite(where_element(file, "triangle", facet), p);
      soup.add_vertex(p);
    }
    soup.add_triangle(first, first + 1, first + 2);
  }
  return soup.finish();
}

double parse_coordinate(const TokenReader& tokens, std::string_view token) {
  double value = 0;
  if (!parse_double(token, value)) {
    throw FormatError(where_line(tokens.file()) + "expected a number, got " + quote_token(token));
  }
  return value;
}

void expect_keyword(TokenReader& tokens, std::string_view keyword) {
  std::string what(1, '\'');
  what.append(keyword).append(1, '\'');
  const std::string_view token = tokens.expect(what);
  if (token != keyword) {
    throw FormatError(where_line(tokens.file()) + "expected '" + std::string(keyword) + "', got " +
                      quote_token(token));
  }
}

TriangleSoup read_ascii_stl(InputFile& file, ReadReport& report, const SoupChunks* chunks) {
  report.encoding = "ascii";
  SoupBuilder soup(file.name(), report, chunks);
  soup.vertices_unshared();
  soup.begin_part(file.path().stem().string());
  TokenReader tokens(file);
  std::vector<std::uint32_t> corners;
  bool inside_solid = false;
  for (std::string_view token = tokens.next(); !token.empty(); token = tokens.next()) {
    if (token == "solid" && !inside_solid) {
      tokens.skip_line();  // the solid's name, any text
      inside_solid = true;
    } else if (token == "endsolid" && inside_solid) {
      tokens.skip_line();
      inside_solid = false;
    } else if (token == "facet" && inside_solid) {
      expect_keyword(tokens, "normal");
      for (int i = 0; i < 3; ++i) parse_coordinate(tokens, tokens.expect("a normal component"));
      expect_keyword(tokens, "outer");
      expect_keyword(tokens, "loop");
      corners.clear();
      for (token = tokens.expect("'vertex'"); token == "vertex";
           token = tokens.expect("'endloop'")) {
        Vec3 p{};
        for (double& coordinate : p)
          coordinate = parse_coordinate(tokens, tokens.expect("a coordinate"));
        if (!is_finite(p)) throw_not_finite(where_line(file), p);
        if (soup.vertex_count() >= max_vertices)
          throw InputError(where_line(file) + "more vertices than a soup can index");
        corners.push_back(static_cast<std::uint32_t>(soup.vertex_count()));
        soup.add_vertex(p);
      }
      if (token != "endloop") {
        throw FormatError(where_line(file) + "expected 'vertex' or 'endloop', got " +
                          quote_token(token));
      }
      if (corners.size() < 3) {
        throw FormatError(where_line(file) + "facet has " + std::to_string(corners.size()) +
                          " vertices, needs 3");
      }
      expect_keyword(tokens, "endfacet");
      soup.add_polygon(corners);
    } else {
      throw FormatError(
          where_line(file) + "unexpected " + quote_token(token) +
          (inside_solid ? " (expected 'facet' or 'endsolid')" : " (expected 'solid')"));
    }
  }
  if (inside_solid) throw FormatError(file.name() + ": the file ends without 'endsolid'");
  return soup.finish();
}

}  // namespace

std::optional<std::uint64_t> binary_stl_count(InputFile& file) {
  const std::string_view head = file.peek(header_bytes);
  if (head.size() != header_bytes) return std::nullopt;
  const std::uint64_t count = load_scalar<std::uint32_t>(head.data() + 80, false);
  if (file.size() != header_bytes + facet_bytes * count) return std::nullopt;
  return count;
}

TriangleSoup read_stl(InputFile& file, ReadReport& report, const SoupChunks* chunks) {
  if (const auto count = binary_stl_count(file)) return read_binary_stl(file, report, *count, chunks);
  const std::string_view head = file.peek(header_bytes);
  std::string_view text = head;
  while (!text.empty() && (is_space(text.front()) || text.front() == '\n')) text.remove_prefix(1);
  // ASCII STL never holds a NUL byte; a binary header usually does (zero padding).
  const bool looks_binary = head.find('\0') != std::string_view::npos;
  if (text.starts_with("solid") && !looks_binary) return read_ascii_stl(file, report, chunks);
  if (head.size() < header_bytes) {
    throw FormatError(file.name() + ": not an STL file: " + std::to_string(file.size()) +
                      " bytes, too short for a binary STL (84-byte header) and not ASCII "
                      "(no 'solid')");
  }
  const std::uint64_t count = load_scalar<std::uint32_t>(head.data() + 80, false);
  throw FormatError(file.name() + ": truncated or corrupt binary STL: the header announces " +
                    std::to_string(count) + " triangles, expected " +
                    std::to_string(header_bytes + facet_bytes * count) + " bytes, the file has " +
                    std::to_string(file.size()) + " bytes");
}

}  // namespace tetrapage::detail
