// The mesh readers on small files written here, byte by byte where the format is binary,
// checked against the data the files were made from; the real meshes against CGAL's reader.

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Exact_rational.h>
#include <CGAL/IO/polygon_soup_io.h>

#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <sstream>

#include "TestSupport.h"
#include "tetrapage/formats/mesh/MeshWriter.h"

namespace tetrapage::test {
namespace {

// ---------------------------------------------------------------------------------------
// OBJ

TEST(ObjReader, VerticesFacesPolygonsAndNegativeIndices) {
  const auto folder = scratch_folder("obj_basic");
  const auto path = folder / "bracket.obj";
  write_file(path,
             "# a comment\n"
             "mtllib bracket.mtl\n"
             "o bracket\n"
             "g group\n"
             "v 0 0 0\n"
             "v 1.5 0 0 1.0\n"   // w is ignored
             "v\t1.5  2.25 0\n"  // tabs and double spaces
             "v 0 2.25 -0.125\n"
             "vt 0.5 0.5\n"
             "vn 0 0 1\n"
             "usemtl steel\n"
             "s off\n"
             "f 1 2 3\n"                    // plain
             "f 1/1 3/1 4/1\n"              // i/t
             "v 3 3 3\r\n"                  // CRLF line end
             "f -5//1 -4//1 -1//1\n"        // negative: vertices 1, 2, 5
             "f 1/1/1 2/1/1 5/1/1 4/1/1\n"  // a quad, i/t/n
             "f 2 3 5 4 1\n");              // a pentagon
  ReadReport report;
  const TriangleSoup soup = read_mesh(path, &report);

  const std::vector<Vec3> vertices = {
      {0, 0, 0}, {1.5, 0, 0}, {1.5, 2.25, 0}, {0, 2.25, -0.125}, {3, 3, 3}};
  ASSERT_EQ(soup.vertices, vertices);
  // Fan triangulation around the first corner: (a b c d) -> abc acd.
  const std::vector<TriangleIndices> triangles = {{0, 1, 2}, {0, 2, 3}, {0, 1, 4}, {0, 1, 4},
                                                  {0, 4, 3}, {1, 2, 4}, {1, 4, 3}, {1, 3, 0}};
  ASSERT_EQ(soup.triangles, triangles);
  // Every face is in group "group" of object "bracket": one part.
  EXPECT_EQ(soup.part_names, std::vector<std::string>{"group"});
  EXPECT_EQ(soup.part_paths, std::vector<std::string>{"bracket/group"});
  EXPECT_EQ(soup.part_of, std::vector<std::uint32_t>(triangles.size(), 0));
  EXPECT_EQ(report.format, "obj");
  EXPECT_EQ(report.encoding, "ascii");
  EXPECT_EQ(report.path, path.string());
  EXPECT_EQ(report.bytes, std::filesystem::file_size(path));
  EXPECT_EQ(report.triangles_read, 8u);
  EXPECT_EQ(report.polygons_triangulated, 2u);
  EXPECT_EQ(report.degenerate_dropped, 0u);
  EXPECT_GE(report.seconds, 0.0);
}

TEST(ObjReader, LastLineWithoutNewlineAndSignedNumbers) {
  const auto folder = scratch_folder("obj_last_line");
  const auto path = folder / "t.obj";
  write_file(path, "v +1e-9 -2.5E+3 0x1\nv 1 0 0\nv 0 1 0\nf 1 2 3");
  // "0x1" is not a number: a FormatError naming line 1.
  expect_error<FormatError>([&] { read_mesh(path); }, {path.string(), "line 1", "0x1"});
  // A UTF-8 byte-order mark before the first line is not part of it.
  write_file(path, "\xEF\xBB\xBFv +1e-9 -2.5E+3 7\nv 1 0 0\nv 0 1 0\nf 1 2 3");
  const TriangleSoup soup = read_mesh(path);
  ASSERT_EQ(soup.triangle_count(), 1u);
  EXPECT_EQ(soup.vertices[0], (Vec3{1e-9, -2500.0, 7.0}));
}

TEST(ObjReader, ErrorsNameFileLineAndValue) {
  const auto folder = scratch_folder("obj_errors");
  const auto path = folder / "bad.obj";
  write_file(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
  expect_error<InputError>([&] { read_mesh(path); },
                           {path.string(), "line 4", "4", "out of range"});
  write_file(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n");
  expect_error<InputError>([&] { read_mesh(path); }, {path.string(), "line 4", "-4"});
  write_file(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
  expect_error<InputError>([&] { read_mesh(path); }, {path.string(), "line 4", "index 0"});
  // A forward reference: vertex 4 is defined after the face.
  write_file(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\nv 1 1 1\n");
  expect_error<InputError>([&] { read_mesh(path); }, {path.string(), "line 4"});
  write_file(path, "v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n");
  expect_error<InputError>([&] { read_mesh(path); }, {path.string(), "line 2", "nan"});
  write_file(path, "v 0 0 0\nv 1 0 1e999\nv 0 1 0\nf 1 2 3\n");
  expect_error<InputError>([&] { read_mesh(path); }, {path.string(), "line 2", "inf"});
  write_file(path, "v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n");
  expect_error<FormatError>([&] { read_mesh(path); }, {path.string(), "line 2"});
  write_file(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n");
  expect_error<FormatError>([&] { read_mesh(path); }, {path.string(), "line 4", "2 corners"});
  write_file(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 x 3\n");
  expect_error<FormatError>([&] { read_mesh(path); }, {path.string(), "line 4", "'x'"});
  write_file(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
  expect_error<InputError>([&] { read_mesh(path); }, {path.string(), "no triangle"});
}

TEST(ObjReader, ObjectsAndGroupsBecomeParts) {
  const auto folder = scratch_folder("obj_parts");
  const auto path = folder / "assembly.obj";
  write_file(path,
             "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
             "f 1 2 3\n"  // t0: before any o/g, the stem's part
             "o frame\n"
             "f 1 2 4\n"  // t1: the object's own part
             "g left\n"
             "f 1 3 4\n"           // t2: frame/left
             "g  empty group  \n"  // no face: no part
             "g right side \n"     // one group, the name trimmed
             "f 2 3 4\n"           // t3: frame/right side
             "g left\n"
             "f 1 2 3 4\n"  // t4, t5: frame/left again (a quad)
             "g\n"
             "f 1 2 4\n"  // t6: back to the object's part
             "o\n"
             "g loose\n"
             "f 1 3 4\n"  // t7: a group outside any object
             "o frame\n"
             "g left\n"
             "f 2 3 4\n");  // t8: frame/left once more
  const TriangleSoup soup = read_mesh(path);
  EXPECT_EQ(soup.part_names,
            (std::vector<std::string>{"assembly", "frame", "left", "right side", "loose"}));
  EXPECT_EQ(soup.part_paths, (std::vector<std::string>{"assembly", "frame", "frame/left",
                                                       "frame/right side", "loose"}));
  EXPECT_EQ(soup.part_of, (std::vector<std::uint32_t>{0, 1, 2, 3, 2, 2, 1, 4, 2}));

  // Without o or g: one part named by the stem, as before parts were read.
  write_file(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\ng\nf 1 2 3\n");
  const TriangleSoup plain = read_mesh(path);
  EXPECT_EQ(plain.part_names, std::vector<std::string>{"assembly"});
  EXPECT_TRUE(plain.part_paths.empty());
}

// The rule of MeshReader.h, written another way: the (name, path) of each face from the
// o/g lines above it, parts in the order of their first face.
TEST(ObjReader, PartsFollowTheRuleOnRandomFiles) {
  const auto folder = scratch_folder("obj_parts_random");
  const auto path = folder / "stem.obj";
  const char* objects[] = {"A", "B", "C d"};
  const char* groups[] = {"x", "y z", "w"};
  for (std::uint64_t seed = 1; seed <= 30; ++seed) {
    Random random(seed);
    std::string text = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    std::string object, group;
    std::vector<std::string> names, paths, expected_path_of;
    const auto face = [&] {
      text += "f 1 2 3\n";
      const std::string name = !group.empty() ? group : !object.empty() ? object : "stem";
      const std::string full = object.empty()  ? name
                               : group.empty() ? object
                                               : object + "/" + group;
      if (std::find(paths.begin(), paths.end(), full) == paths.end()) {
        paths.push_back(full);
        names.push_back(name);
      }
      expected_path_of.push_back(full);
    };
    for (int line = 0; line < 60; ++line) {
      const double u = random.uniform();
      const std::string pad(random.below(3), ' ');
      if (u < 0.1) {
        object = objects[random.below(3)];
        group.clear();
        text += "o " + pad + object + pad + "\n";
      } else if (u < 0.13) {
        object.clear();
        group.clear();
        text += "o\n";
      } else if (u < 0.3) {
        group = groups[random.below(3)];
        text += "g" + pad + " " + group + pad + "\n";
      } else if (u < 0.33) {
        group.clear();
        text += "g\n";
      } else {
        face();
      }
    }
    face();
    write_file(path, text);
    const TriangleSoup soup = read_mesh(path);
    ASSERT_EQ(soup.part_names, names) << "seed " << seed << "\n" << text;
    ASSERT_EQ(soup.part_count(), paths.size());
    for (std::size_t p = 0; p < paths.size(); ++p) EXPECT_EQ(soup.part_path(p), paths[p]);
    ASSERT_EQ(soup.part_of.size(), expected_path_of.size());
    for (std::size_t t = 0; t < expected_path_of.size(); ++t)
      ASSERT_EQ(soup.part_path(soup.part_of[t]), expected_path_of[t])
          << "seed " << seed << " face " << t;
  }
}

// ---------------------------------------------------------------------------------------
// STL

std::string binary_stl(const std::vector<std::array<std::array<float, 3>, 3>>& facets,
                       std::string_view header_text = "made by a test") {
  Bytes bytes;
  std::string header(80, '\0');
  header.replace(0, header_text.size(), header_text);
  bytes.text(header).put<std::uint32_t>(static_cast<std::uint32_t>(facets.size()));
  for (const auto& facet : facets) {
    for (int k = 0; k < 3; ++k) bytes.put<float>(0.0f);  // normal, ignored
    for (const auto& corner : facet)
      for (float c : corner) bytes.put<float>(c);
    bytes.put<std::uint16_t>(0);
  }
  return bytes.str();
}

TEST(StlReader, BinaryEvenWhenTheHeaderSaysSolid) {
  const auto folder = scratch_folder("stl_binary");
  const std::vector<std::array<std::array<float, 3>, 3>> facets = {
      {{{0, 0, 0}, {1.1f, 0, 0}, {0, 1, 0}}}, {{{0, 0, 1}, {1, 0, 1}, {0, 1.7f, 1}}}};
  for (const std::string_view header : {"made by a test", "solid looks like ascii"}) {
    const auto path = folder / "part.stl";
    write_file(path, binary_stl(facets, header));
    ReadReport report;
    const TriangleSoup soup = read_mesh(path, &report);
    ASSERT_EQ(soup.triangle_count(), 2u) << header;
    for (std::size_t t = 0; t < 2; ++t) {
      for (int k = 0; k < 3; ++k) {
        const Vec3 expected{facets[t][k][0], facets[t][k][1], facets[t][k][2]};
        EXPECT_EQ(soup.corners(t)[k], expected);
      }
    }
    EXPECT_EQ(report.format, "stl");
    EXPECT_EQ(report.encoding, "binary");
    EXPECT_EQ(report.bytes, 84u + 2 * 50u);
    EXPECT_EQ(soup.part_names, std::vector<std::string>{"part"});
  }
}

TEST(StlReader, AsciiWithSeveralSolids) {
  const auto folder = scratch_folder("stl_ascii");
  const auto path = folder / "two.stl";
  write_file(path,
             "solid first one\n"
             "  facet normal 0 0 1\n    outer loop\n"
             "      vertex 0 0 0\n      vertex 1.25 0 0\n      vertex 0 1e-3 0\n"
             "    endloop\n  endfacet\n"
             "endsolid first one\n"
             "solid\r\n"
             "facet normal 0 0 0 outer loop vertex 0 0 5 vertex 1 0 5 vertex 1 1 5 vertex 0 1 5 "
             "endloop endfacet\n"  // a quad facet, all on one line
             "endsolid\n");
  ReadReport report;
  const TriangleSoup soup = read_mesh(path, &report);
  ASSERT_EQ(soup.triangle_count(), 3u);
  EXPECT_EQ(soup.corners(0)[1], (Vec3{1.25, 0, 0}));
  EXPECT_EQ(soup.corners(0)[2], (Vec3{0, 1e-3, 0}));  // ASCII keeps doubles
  EXPECT_EQ(soup.corners(2)[2], (Vec3{0, 1, 5}));
  EXPECT_EQ(report.encoding, "ascii");
  EXPECT_EQ(report.polygons_triangulated, 1u);
}

TEST(StlReader, ErrorsNameFileAndPlace) {
  const auto folder = scratch_folder("stl_errors");
  const auto path = folder / "bad.stl";
  const std::vector<std::array<std::array<float, 3>, 3>> facets = {
      {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}}, {{{0, 0, 1}, {1, 0, 1}, {0, 1, 1}}}};
  std::string bytes = binary_stl(facets);
  write_file(path, bytes.substr(0, bytes.size() - 7));  // truncated
  expect_error<FormatError>([&] { read_mesh(path); },
                            {path.string(), "2 triangles", "expected 184 bytes", "177 bytes"});
  write_file(path, binary_stl(facets, "solid but binary").substr(0, 150));
  expect_error<FormatError>([&] { read_mesh(path); }, {path.string(), "expected 184", "150"});
  write_file(path, "hello");
  expect_error<FormatError>([&] { read_mesh(path); }, {path.string(), "5 bytes"});

  auto with_nan = facets;
  with_nan[1][2][1] = std::numeric_limits<float>::quiet_NaN();
  write_file(path, binary_stl(with_nan));
  expect_error<InputError>([&] { read_mesh(path); }, {path.string(), "triangle 1", "nan"});

  write_file(path,
             "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
             "vertex 0 1 zero\nendloop\nendfacet\nendsolid\n");
  expect_error<FormatError>([&] { read_mesh(path); }, {path.string(), "line 6", "'zero'"});
  write_file(path,
             "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
             "vertex 0 1 0\nendloop\nendfacet\n");
  expect_error<FormatError>([&] { read_mesh(path); }, {path.string(), "endsolid"});
  write_file(path,
             "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
             "endloop\nendfacet\nendsolid\n");
  expect_error<FormatError>([&] { read_mesh(path); }, {path.string(), "line 6", "2 vertices"});
  write_file(path,
             "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 inf\n"
             "vertex 0 1 0\nendloop\nendfacet\nendsolid\n");
  expect_error<InputError>([&] { read_mesh(path); }, {path.string(), "line 5", "inf"});
}

// ---------------------------------------------------------------------------------------
// PLY

enum class Encoding { ascii, little, big };

const char* encoding_name(Encoding encoding) {
  switch (encoding) {
    case Encoding::ascii:
      return "ascii";
    case Encoding::little:
      return "binary_little_endian";
    case Encoding::big:
      return "binary_big_endian";
  }
  return "";
}

/// Writes one value of PLY type `type` either as text or as bytes.
void put_value(Encoding encoding, std::string& text, Bytes& bytes, const std::string& type,
               double value) {
  if (encoding == Encoding::ascii) {
    std::ostringstream out;
    out.precision(17);
    out << value << ' ';
    text += out.str();
    return;
  }
  if (type == "char" || type == "int8")
    bytes.put<std::int8_t>(static_cast<std::int8_t>(value));
  else if (type == "uchar" || type == "uint8")
    bytes.put<std::uint8_t>(static_cast<std::uint8_t>(value));
  else if (type == "short" || type == "int16")
    bytes.put<std::int16_t>(static_cast<std::int16_t>(value));
  else if (type == "ushort" || type == "uint16")
    bytes.put<std::uint16_t>(static_cast<std::uint16_t>(value));
  else if (type == "int" || type == "int32")
    bytes.put<std::int32_t>(static_cast<std::int32_t>(value));
  else if (type == "uint" || type == "uint32")
    bytes.put<std::uint32_t>(static_cast<std::uint32_t>(value));
  else if (type == "float" || type == "float32")
    bytes.put<float>(static_cast<float>(value));
  else if (type == "double" || type == "float64")
    bytes.put<double>(value);
  else
    ADD_FAILURE() << "bad type " << type;
}

struct PlyCase {
  Encoding encoding;
  std::string coordinate_type;  ///< type of x, y, z
  std::string count_type;       ///< face list count type
  std::string index_type;       ///< face list index type
  std::string list_name;        ///< vertex_indices or vertex_index
};

/// A PLY file with extra elements and properties around the ones the reader keeps:
/// a "material" element first, vertices with normal and colour (and a list), faces with a
/// colour before and a flag after the corner list, and an "edge" element at the end.
std::string make_ply(const PlyCase& c, const std::vector<Vec3>& vertices,
                     const std::vector<std::vector<std::int64_t>>& faces) {
  std::string header = "ply\nformat " + std::string(encoding_name(c.encoding)) +
                       " 1.0\ncomment test file\nobj_info generated\n";
  header += "element material 2\nproperty uchar red\nproperty list uchar float weights\n";
  header += "element vertex " + std::to_string(vertices.size()) + "\n";
  header += "property " + c.coordinate_type + " x\nproperty float nx\nproperty " +
            c.coordinate_type +
            " y\nproperty uchar red\nproperty list uchar short tags\n"
            "property " +
            c.coordinate_type + " z\nproperty double quality\n";
  header += "element face " + std::to_string(faces.size()) + "\n";
  header += "property uchar red\nproperty list " + c.count_type + " " + c.index_type + " " +
            c.list_name + "\nproperty int flags\n";
  header += "element edge 1\nproperty int vertex1\nproperty int vertex2\n";
  header += "end_header\n";
  std::string text;
  Bytes bytes(c.encoding == Encoding::big);
  const auto line_end = [&] {
    if (c.encoding == Encoding::ascii) text += "\n";
  };
  for (int m = 0; m < 2; ++m) {
    put_value(c.encoding, text, bytes, "uchar", 200 + m);
    put_value(c.encoding, text, bytes, "uchar", m + 1);
    for (int k = 0; k <= m; ++k) put_value(c.encoding, text, bytes, "float", 0.5 * k);
    line_end();
  }
  for (const auto& v : vertices) {
    put_value(c.encoding, text, bytes, c.coordinate_type, v[0]);
    put_value(c.encoding, text, bytes, "float", 0.25);
    put_value(c.encoding, text, bytes, c.coordinate_type, v[1]);
    put_value(c.encoding, text, bytes, "uchar", 7);
    put_value(c.encoding, text, bytes, "uchar", 2);
    put_value(c.encoding, text, bytes, "short", -3);
    put_value(c.encoding, text, bytes, "short", 4);
    put_value(c.encoding, text, bytes, c.coordinate_type, v[2]);
    put_value(c.encoding, text, bytes, "double", 0.75);
    line_end();
  }
  for (const auto& face : faces) {
    put_value(c.encoding, text, bytes, "uchar", 9);
    put_value(c.encoding, text, bytes, c.count_type, static_cast<double>(face.size()));
    for (auto index : face)
      put_value(c.encoding, text, bytes, c.index_type, static_cast<double>(index));
    put_value(c.encoding, text, bytes, "int", -1);
    line_end();
  }
  put_value(c.encoding, text, bytes, "int", 0);
  put_value(c.encoding, text, bytes, "int", 1);
  line_end();
  return header + (c.encoding == Encoding::ascii ? text : bytes.str());
}

void PrintTo(const PlyCase& c, std::ostream* out) {
  *out << encoding_name(c.encoding) << " x/y/z " << c.coordinate_type << ", list " << c.count_type
       << " " << c.index_type << " " << c.list_name;
}

class PlyReaderTest : public ::testing::TestWithParam<PlyCase> {};

TEST_P(PlyReaderTest, KeepsCoordinatesAndCornersSkipsTheRest) {
  const PlyCase& c = GetParam();
  const auto folder = scratch_folder("ply_case");
  const auto path = folder / "plate.ply";
  // Values every coordinate type holds exactly (the integer types too).
  const bool integral = c.coordinate_type != "float" && c.coordinate_type != "double" &&
                        c.coordinate_type != "float32" && c.coordinate_type != "float64";
  const bool is_unsigned = c.coordinate_type.starts_with("u");
  const double fraction = integral ? 0.0 : 0.5;
  const double sign = is_unsigned ? 1.0 : -1.0;
  std::vector<Vec3> vertices = {{0, 0, 0},
                                {10 + fraction, 0, 0},
                                {10 + fraction, 20, sign * 3},
                                {0, 20 - fraction, 1},
                                {5, 25, 2 + fraction}};
  if (c.coordinate_type == "double" || c.coordinate_type == "float64")
    vertices[4] = {0.1, 1e-300, -1e300};  // only a double holds these
  const std::vector<std::vector<std::int64_t>> faces = {{0, 1, 2}, {0, 2, 3, 4}, {1, 2, 4}};
  write_file(path, make_ply(c, vertices, faces));
  ReadReport report;
  const TriangleSoup soup = read_mesh(path, &report);
  ASSERT_EQ(soup.vertices, vertices);
  const std::vector<TriangleIndices> triangles = {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {1, 2, 4}};
  EXPECT_EQ(soup.triangles, triangles);
  EXPECT_EQ(report.format, "ply");
  EXPECT_EQ(report.encoding, encoding_name(c.encoding));
  EXPECT_EQ(report.triangles_read, 4u);
  EXPECT_EQ(report.polygons_triangulated, 1u);
  EXPECT_EQ(soup.part_names, std::vector<std::string>{"plate"});
}

std::vector<PlyCase> ply_cases() {
  std::vector<PlyCase> cases;
  for (Encoding encoding : {Encoding::ascii, Encoding::little, Encoding::big}) {
    for (const char* type : {"float", "double", "char", "uchar", "short", "ushort", "int", "uint",
                             "float32", "float64", "int16"}) {
      cases.push_back({encoding, type, "uchar", "int", "vertex_indices"});
    }
    cases.push_back({encoding, "float", "int", "uint", "vertex_index"});
    cases.push_back({encoding, "double", "ushort", "ushort", "vertex_indices"});
    cases.push_back({encoding, "float", "uint8", "uint32", "vertex_indices"});
    cases.push_back({encoding, "float", "char", "short", "vertex_index"});
  }
  return cases;
}

INSTANTIATE_TEST_SUITE_P(Layouts, PlyReaderTest, ::testing::ValuesIn(ply_cases()),
                         [](const auto& param_info) {
                           const PlyCase& c = param_info.param;
                           return std::string(encoding_name(c.encoding)) + "_" + c.coordinate_type +
                                  "_" + c.count_type + "_" + c.index_type + "_" + c.list_name;
                         });

TEST(PlyReader, ErrorsNameFileElementAndValue) {
  const auto folder = scratch_folder("ply_errors");
  const auto path = folder / "bad.ply";
  const std::vector<Vec3> vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const PlyCase little{Encoding::little, "float", "uchar", "int", "vertex_indices"};
  const PlyCase ascii{Encoding::ascii, "float", "uchar", "int", "vertex_indices"};

  // Truncated binary: cut inside the face element.
  std::string bytes = make_ply(little, vertices, {{0, 1, 2}, {0, 1, 2}});
  write_file(path, bytes.substr(0, bytes.size() - 8 - 10));
  expect_error<FormatError>([&] { read_mesh(path); },
                            {path.string(), "face 1", "truncated", "needs", "bytes"});
  // Index out of range, binary and ASCII.
  write_file(path, make_ply(little, vertices, {{0, 1, 2}, {0, 3, 1}}));
  expect_error<InputError>([&] { read_mesh(path); }, {path.string(), "face 1", "index 3"});
  write_file(path, make_ply(ascii, vertices, {{0, 1, 2}, {0, -1, 1}}));
  expect_error<InputError>([&] { read_mesh(path); }, {path.string(), "face 1", "index -1"});
  // NaN coordinates.
  write_file(path, make_ply(little, {{0, 0, 0}, {1, std::nan(""), 0}, {0, 1, 0}}, {{0, 1, 2}}));
  expect_error<InputError>([&] { read_mesh(path); }, {path.string(), "vertex 1", "nan"});
  write_file(path, make_ply(ascii, {{0, 0, 0}, {1, 0, 0}, {0, 1, INFINITY}}, {{0, 1, 2}}));
  expect_error<InputError>([&] { read_mesh(path); }, {path.string(), "vertex 2", "inf"});
  // ASCII: a word where a number should be (x of vertex 0), and a file that ends early.
  std::string text;
  text = make_ply(ascii, vertices, {{0, 1, 2}});
  std::string broken = text;
  const auto vertex_line = broken.find('\n', broken.find("end_header"));
  const auto second_line = broken.find('\n', vertex_line + 1) + 1;  // after the 1st material
  const auto third_line = broken.find('\n', second_line) + 1;       // first vertex line
  broken.replace(third_line, 1, "q");
  write_file(path, broken);
  expect_error<FormatError>([&] { read_mesh(path); }, {path.string(), "line", "'q", "vertex 0"});
  write_file(path, text.substr(0, text.size() - 10));
  expect_error<FormatError>([&] { read_mesh(path); }, {path.string(), "ends inside"});
  // Header problems.
  write_file(path, "ply\nformat ascii 1.0\nelement vertex 3\nproperty flot x\nend_header\n");
  expect_error<FormatError>([&] { read_mesh(path); }, {path.string(), "line 4", "'flot'"});
  write_file(path, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n");
  expect_error<FormatError>([&] { read_mesh(path); }, {path.string(), "end_header"});
  write_file(path, "ply\nformat ascii 1.0\nelemnt vertex 3\nend_header\n");
  expect_error<FormatError>([&] { read_mesh(path); }, {path.string(), "line 3", "'elemnt'"});
  write_file(path, "plx\n");
  expect_error<FormatError>([&] { read_mesh(path); }, {path.string(), "not a PLY"});
  write_file(path,
             "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
             "end_header\n1 2\n");
  expect_error<FormatError>([&] { read_mesh(path); }, {path.string(), "'z'"});
  // No face element: no triangle.
  write_file(path,
             "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
             "property float z\nend_header\n1 2 3\n");
  expect_error<InputError>([&] { read_mesh(path); }, {path.string(), "no triangle"});
}

// Our writer's part table, in ASCII here (MeshWriter writes it binary: MeshWriter_test), after
// the faces as MeshWriter places it, or before them.
TEST(PlyReader, APartTableMakesParts) {
  const auto folder = scratch_folder("ply_parts");
  const auto path = folder / "plate.ply";
  const std::string vertices =
      "element vertex 4\nproperty double x\nproperty double y\nproperty double z\n";
  const std::string faces = "element face 3\nproperty list uchar int vertex_indices\n";
  const std::string table =
      "element part 3\nproperty uint faces\nproperty list uchar uchar name\n"
      "property list uchar uchar path\n";
  const std::string vertex_data = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
  const std::string face_data = "3 0 1 2\n4 0 1 3 2\n3 1 2 3\n";  // a quad between triangles
  // Parts "a" (1 face), "" (none: named by the stem) and "b" at path "r/b" (2 faces).
  const std::string table_data = "1 1 97 0\n0 0 0\n2 1 98 3 114 47 98\n";
  const auto write = [&](const std::string& table_header, const std::string& records, bool after) {
    write_file(path, "ply\nformat ascii 1.0\n" + vertices +
                         (after ? faces + table_header : table_header + faces) + "end_header\n" +
                         vertex_data + (after ? face_data + records : records + face_data));
  };
  for (const bool after : {true, false}) {
    SCOPED_TRACE(after ? "after the faces" : "before the faces");
    write(table, table_data, after);
    const TriangleSoup soup = read_mesh(path);
    EXPECT_EQ(soup.part_names, (std::vector<std::string>{"a", "plate", "b"}));
    EXPECT_EQ(soup.part_path(2), "r/b");
    // f0 -> "a"; the quad's two triangles and f2 -> "b".
    EXPECT_EQ(soup.part_of, (std::vector<std::uint32_t>{0, 2, 2, 2}));
    // Counts that do not add up to the faces.
    write(table, "1 1 97 0\n0 0 0\n1 1 98 0\n", after);
    expect_error<FormatError>([&] { read_mesh(path); }, {path.string(), "counts 2 faces", "has 3"});
    write(table, "4294967295 1 97 0\n0 0 0\n4294967295 1 98 0\n", after);
    expect_error<FormatError>([&] { read_mesh(path); }, {path.string(), "counts more faces"});
  }
  // An element "part" of another shape is some other tool's: skipped.
  write("element part 1\nproperty float faces\nproperty list uchar uchar name\n", "3.5 1 97\n",
        true);
  EXPECT_EQ(read_mesh(path).part_names, std::vector<std::string>{"plate"});
}

// ---------------------------------------------------------------------------------------
// OFF

TEST(OffReader, CommentsColoursAndKeywordOnTheCountsLine) {
  const auto folder = scratch_folder("off_basic");
  const auto path = folder / "box.off";
  write_file(path,
             "# leading comment\n"
             "OFF 5 3 0   # counts on the keyword's line\n"
             "\n"
             "0 0 0\n1 0 0 # trailing comment\n1 1 0\n0 1 0\n0.5 0.5 1e-7\n"
             "4 0 1 2 3 255 0 0\n"      // quad with an RGB colour
             "3 0 1 4 0.5 0.5 0.5 1\n"  // RGBA floats
             "3 1 2 4\n");
  ReadReport report;
  const TriangleSoup soup = read_mesh(path, &report);
  EXPECT_EQ(soup.vertices.size(), 5u);
  EXPECT_EQ(soup.vertices[4], (Vec3{0.5, 0.5, 1e-7}));
  const std::vector<TriangleIndices> triangles = {{0, 1, 2}, {0, 2, 3}, {0, 1, 4}, {1, 2, 4}};
  EXPECT_EQ(soup.triangles, triangles);
  EXPECT_EQ(report.polygons_triangulated, 1u);
  EXPECT_EQ(report.format, "off");

  // COFF: colours after x y z on vertex lines; counts on the next line.
  write_file(path, "COFF\n3 1 0\n0 0 0 1 0 0 1\n1 0 0 0 1 0 1\n0 1 0 0 0 1 1\n3 0 1 2\n");
  EXPECT_EQ(read_mesh(path).triangle_count(), 1u);
}

TEST(OffReader, ErrorsNameFileLineAndValue) {
  const auto folder = scratch_folder("off_errors");
  const auto path = folder / "bad.off";
  write_file(path, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
  expect_error<InputError>([&] { read_mesh(path); }, {path.string(), "line 6", "index 3"});
  write_file(path, "OFF\n3 1 0\n0 0 0\n1 0 0\n");
  expect_error<FormatError>([&] { read_mesh(path); }, {path.string(), "2 of 3 vertices"});
  write_file(path, "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  expect_error<FormatError>([&] { read_mesh(path); }, {path.string(), "1 of 2 faces"});
  // Counts the file's size cannot hold: every vertex and face takes a line.
  write_file(path, "OFF\n3 100 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  expect_error<FormatError>([&] { read_mesh(path); }, {path.string(), "line 2", "100 faces", "26 bytes"});
  write_file(path, "OFF\nthree 1 0\n");
  expect_error<FormatError>([&] { read_mesh(path); }, {path.string(), "line 2", "three"});
  write_file(path, "OFF\n3 1 0\n0 0 0\n1 -nan 0\n0 1 0\n3 0 1 2\n");
  expect_error<InputError>([&] { read_mesh(path); }, {path.string(), "line 4", "nan"});
  write_file(path, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1\n");
  expect_error<FormatError>([&] { read_mesh(path); }, {path.string(), "line 6"});
  write_file(path, "4OFF\n3 1 0\n");
  expect_error<FormatError>([&] { read_mesh(path); }, {path.string(), "4OFF"});
  write_file(path, "PLY\n3 1 0\n");
  expect_error<FormatError>([&] { read_mesh(path); }, {path.string(), "'PLY'"});
}

// ---------------------------------------------------------------------------------------
// Shared behaviour

TEST(MeshReader, DegenerateTrianglesAreDroppedAndCounted) {
  const auto folder = scratch_folder("degenerate");
  const auto path = folder / "d.off";
  // 0: fine; 1: repeated index; 2: collinear corners; 3: two corners at the same point;
  // 4: fine but nearly flat (one ulp off the line), which must be kept.
  const double off_line = std::nextafter(4.0, 5.0);
  std::ostringstream text;
  text.precision(17);
  text << "OFF\n7 5 0\n0 0 0\n1 0 0\n0 1 0\n2 2 2\n3 3 3\n0 0 0\n4 4 " << off_line << "\n"
       << "3 0 1 2\n3 0 1 1\n3 0 3 4\n3 0 5 1\n3 0 3 6\n";
  write_file(path, text.str());
  ReadReport report;
  const TriangleSoup soup = read_mesh(path, &report);
  EXPECT_EQ(soup.triangles, (std::vector<TriangleIndices>{{0, 1, 2}, {0, 3, 6}}));
  EXPECT_EQ(soup.part_of.size(), 2u);
  EXPECT_EQ(report.triangles_read, 5u);
  EXPECT_EQ(report.degenerate_dropped, 3u);

  write_file(path, "OFF\n3 2 0\n0 0 0\n1 1 1\n2 2 2\n3 0 1 2\n3 0 0 1\n");
  expect_error<InputError>([&] { read_mesh(path); },
                           {path.string(), "no triangle left", "2 degenerate"});
}

// A triangle id maps back to the file's face: the faces fan-triangulated in order give the
// positions, triangle_position() skips the dropped ones. The expectation is built here from
// the faces, with degeneracy decided by this test's own integer cross products.
TEST(MeshReader, TriangleIdsMapBackToTheFilesFaces) {
  const auto folder = scratch_folder("triangle_ids");
  const std::vector<std::array<int, 3>> points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                                  {2, 0, 0}, {1, 3, 0}, {0, 0, 1}};
  // A triangle, a quad, a collinear triangle, a pentagon, a repeated corner, a triangle.
  const std::vector<std::vector<int>> faces = {{0, 1, 2},       {0, 1, 2, 3}, {0, 1, 4},
                                               {0, 1, 2, 5, 3}, {0, 0, 6},    {1, 2, 6}};
  struct Fan {
    std::size_t face;
    std::array<int, 3> corners;
    bool degenerate;
  };
  std::vector<Fan> fans;
  for (std::size_t f = 0; f < faces.size(); ++f) {
    for (std::size_t j = 1; j + 1 < faces[f].size(); ++j) {
      const std::array<int, 3> c = {faces[f][0], faces[f][j], faces[f][j + 1]};
      std::array<int, 3> u{}, v{};
      for (int a = 0; a < 3; ++a) {
        u[a] = points[c[1]][a] - points[c[0]][a];
        v[a] = points[c[2]][a] - points[c[0]][a];
      }
      const bool flat =
          u[1] * v[2] == u[2] * v[1] && u[2] * v[0] == u[0] * v[2] && u[0] * v[1] == u[1] * v[0];
      fans.push_back({f, c, flat});
    }
  }
  std::vector<std::uint64_t> dropped;
  for (std::size_t r = 0; r < fans.size(); ++r)
    if (fans[r].degenerate) dropped.push_back(r);
  ASSERT_EQ(dropped.size(), 2u);  // the collinear triangle and the repeated corner

  std::string obj,
      off = "OFF\n" + std::to_string(points.size()) + " " + std::to_string(faces.size()) + " 0\n";
  for (const auto& p : points) {
    const std::string xyz =
        std::to_string(p[0]) + " " + std::to_string(p[1]) + " " + std::to_string(p[2]) + "\n";
    obj += "v " + xyz;
    off += xyz;
  }
  for (const auto& face : faces) {
    obj += "f";
    off += std::to_string(face.size());
    for (int corner : face) {
      obj += " " + std::to_string(corner + 1);
      off += " " + std::to_string(corner);
    }
    obj += "\n";
    off += "\n";
  }
  write_file(folder / "faces.obj", obj);
  write_file(folder / "faces.off", off);
  for (const char* name : {"faces.obj", "faces.off"}) {
    SCOPED_TRACE(name);
    ReadReport report;
    const TriangleSoup soup = read_mesh(folder / name, &report);
    EXPECT_EQ(report.triangles_read, fans.size());
    EXPECT_EQ(report.dropped_positions, dropped);
    ASSERT_EQ(soup.triangle_count(), fans.size() - dropped.size());
    for (std::size_t id = 0; id < soup.triangle_count(); ++id) {
      const std::uint64_t r = triangle_position(report, id);
      ASSERT_LT(r, fans.size());
      EXPECT_FALSE(fans[r].degenerate) << "id " << id;
      const auto corners = soup.corners(id);
      for (int k = 0; k < 3; ++k) {
        const auto& p = points[fans[r].corners[k]];
        EXPECT_EQ(corners[k], (Vec3{double(p[0]), double(p[1]), double(p[2])}))
            << "id " << id << " is a triangle of face " << fans[r].face;
      }
    }
  }
}

TEST(MeshReader, IsDegenerateTriangleAgreesWithExactRationalArithmetic) {
  // Oracle: the cross product in exact rationals is zero iff the corners are collinear. At
  // unit scale and at the extremes of double (products that underflow or overflow), where
  // the inline filter must hand over to the exact test.
  using Q = CGAL::Exact_rational;
  Random random(20240611);
  int collinear = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    const double scale = trial % 3 == 0 ? 1.0 : (trial % 3 == 1 ? 0x1p-1000 : 0x1p+600);
    Vec3 a, b, c;
    for (auto& x : a) x = scale * random.uniform(-1, 1);
    for (auto& x : b) x = scale * random.uniform(-1, 1);
    if (trial % 2 == 0) {
      // On the line through a and b up to rounding: sometimes exactly, mostly not.
      const double t = trial % 4 == 0 ? 0.5 : random.uniform(-2, 2);
      for (int k = 0; k < 3; ++k) c[k] = a[k] + t * (b[k] - a[k]);
      if (trial % 8 == 0) c = a;  // coincident corners
    } else {
      for (auto& x : c) x = scale * random.uniform(-1, 1);
    }
    const Q u[3] = {Q(b[0]) - Q(a[0]), Q(b[1]) - Q(a[1]), Q(b[2]) - Q(a[2])};
    const Q v[3] = {Q(c[0]) - Q(a[0]), Q(c[1]) - Q(a[1]), Q(c[2]) - Q(a[2])};
    const bool expected = u[1] * v[2] - u[2] * v[1] == 0 && u[2] * v[0] - u[0] * v[2] == 0 &&
                          u[0] * v[1] - u[1] * v[0] == 0;
    collinear += expected;
    ASSERT_EQ(is_degenerate_triangle(a, b, c), expected) << "seed 20240611 trial " << trial;
  }
  EXPECT_GT(collinear, 100);  // the test did exercise both answers
  EXPECT_LT(collinear, 3900);
  // Exactly collinear corners whose differences round: a and b on the line x = 3y = 3z / 5
  // through the origin c, at magnitudes 2^50 apart, so that (b - a) is inexact and the cross
  // product in double is often not zero.
  int rounded_nonzero = 0;
  for (int trial = 0; trial < 500; ++trial) {
    const double k1 = std::ldexp(double(random.below(std::uint64_t(1) << 50) + 1), 0);
    const double k2 = std::ldexp(double(random.below(std::uint64_t(1) << 50) + 1), -50);
    const Vec3 a{3 * k1, k1, 5 * k1}, b{3 * k2, k2, 5 * k2}, c{0, 0, 0};
    const double ux = b[0] - a[0], uy = b[1] - a[1], vx = c[0] - a[0], vy = c[1] - a[1];
    rounded_nonzero += ux * vy - uy * vx != 0;
    ASSERT_TRUE(is_degenerate_triangle(a, b, c)) << "trial " << trial;
  }
  EXPECT_GT(rounded_nonzero, 0);  // the filter's error bound was needed
}

TEST(MeshReader, MissingFileAndUnknownExtension) {
  const auto folder = scratch_folder("missing");
  const auto missing = folder / "nothere.obj";
  expect_error<IoError>([&] { read_mesh(missing); }, {missing.string()});
  expect_error<IoError>([&] { read_mesh(folder / "nothere.glb"); }, {"nothere.glb"});
  const auto unknown = folder / "model.xyz123";
  write_file(unknown, "whatever");
  expect_error<InputError>([&] { read_mesh(unknown); }, {unknown.string(), ".xyz123"});
  expect_error<InputError>([&] { mesh_format_from_path("noextension"); }, {"noextension"});
  const auto directory = folder / "folder.obj";
  std::filesystem::create_directories(directory);
  expect_error<IoError>([&] { read_mesh(directory); }, {directory.string()});
  EXPECT_EQ(mesh_format_from_path("a/B.OBJ"), MeshFormat::obj);
  EXPECT_EQ(mesh_format_from_path("a/b.Glb"), MeshFormat::glb);
  EXPECT_EQ(mesh_format_from_path("a/b.3ds"), MeshFormat::assimp_other);
}

TEST(AssimpReader, RawGroupsAreReadWholeOrRefused) {
  // Assimp 5.2's RAW importer leaves a null child in its scene graph for files of several
  // groups: the reader crashed on it. Now each group's triangles are read, or the file is
  // refused by name; never a crash, never a group lost in silence.
  const auto path = scratch_folder("raw_groups") / "two.raw";
  write_file(path, "first\n0 0 0 1 0 0 0 1 0\nsecond\n0 0 1 1 0 1 0 1 1\n");
  try {
    const TriangleSoup soup = read_mesh(path);
    EXPECT_EQ(soup.triangle_count(), 2u);
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("missing node"), std::string::npos) << e.what();
  }
}

// ---------------------------------------------------------------------------------------
// glTF (our reader: GltfReader_test.cpp compares it with Assimp's)

TEST(GltfReader, NodeHierarchyTransformsAndInstances) {
  const auto folder = scratch_folder("gltf_nodes");
  const auto path = folder / "scene.gltf";
  // One triangle mesh used by two nodes: "base" (translation (10,0,0), scale 2) with a child
  // "arm" (translation (0,1,0)), and "copy" at the root with no transform.
  Bytes buffer;
  for (float c : {0.0f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 0.0f, 1.0f, 0.0f}) buffer.put<float>(c);
  for (std::uint32_t i : {0u, 1u, 2u}) buffer.put<std::uint32_t>(i);
  write_file(folder / "scene.bin", buffer.str());
  write_file(path, R"({
    "asset": {"version": "2.0"},
    "scene": 0,
    "scenes": [{"nodes": [0, 2]}],
    "nodes": [
      {"name": "base", "translation": [10, 0, 0], "scale": [2, 2, 2], "children": [1], "mesh": 0},
      {"name": "arm", "translation": [0, 1, 0], "mesh": 0},
      {"name": "copy", "mesh": 0}
    ],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
    "accessors": [
      {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
       "min": [0, 0, 0], "max": [1, 1, 0]},
      {"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"}
    ],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                    {"buffer": 0, "byteOffset": 36, "byteLength": 12}],
    "buffers": [{"uri": "scene.bin", "byteLength": 48}]
  })");
  ReadReport report;
  const TriangleSoup soup = read_mesh(path, &report);
  ASSERT_EQ(soup.part_count(), 3u);
  ASSERT_EQ(soup.triangle_count(), 3u);
  EXPECT_EQ(report.format, "gltf");
  EXPECT_EQ(report.bytes, std::filesystem::file_size(path));
  // Expected world corners per node name: base: 2p + (10,0,0); arm: 2(p + (0,1,0)) + (10,0,0);
  // copy: p.
  std::map<std::string, std::array<Vec3, 3>> expected = {
      {"scene/base", {Vec3{10, 0, 0}, Vec3{12, 0, 0}, Vec3{10, 2, 0}}},
      {"scene/arm", {Vec3{10, 2, 0}, Vec3{12, 2, 0}, Vec3{10, 4, 0}}},
      {"scene/copy", {Vec3{0, 0, 0}, Vec3{1, 0, 0}, Vec3{0, 1, 0}}}};
  for (std::size_t t = 0; t < soup.triangle_count(); ++t) {
    const std::string& name = soup.part_names[soup.part_of[t]];
    ASSERT_EQ(expected.count(name), 1u) << name;
    EXPECT_EQ(soup.corners(t), expected[name]) << name;
  }
}

// ---------------------------------------------------------------------------------------
// Real meshes against CGAL's own reader

TEST(MeshReader, RealOffMeshesAgreeWithCgalReader) {
  using Point = CGAL::Exact_predicates_inexact_constructions_kernel::Point_3;
  int compared = 0;
  for (const char* name :
       {"elephant.off", "fandisk.off", "cow.off", "knot1.off", "P.off", "cube-shuffled.off",
        "corner_poly.off", "blobby-shuffled.off", "mech-holes-shark.off"}) {
    const auto path = std::filesystem::path(TETRAPAGE_MESH_DIR) / name;
    if (!std::filesystem::exists(path)) continue;
    std::vector<Point> points;
    std::vector<std::vector<std::size_t>> polygons;
    ASSERT_TRUE(CGAL::IO::read_polygon_soup(path.string(), points, polygons)) << name;
    ReadReport report;
    const TriangleSoup soup = read_mesh(path, &report);
    ASSERT_EQ(soup.vertices.size(), points.size()) << name;
    for (std::size_t v = 0; v < points.size(); ++v) {
      ASSERT_EQ(soup.vertices[v], (Vec3{points[v].x(), points[v].y(), points[v].z()}))
          << name << " vertex " << v;
    }
    // Fan-triangulate CGAL's polygons and drop degenerate ones independently.
    std::vector<TriangleIndices> expected;
    std::uint64_t read = 0, degenerate = 0;
    for (const auto& polygon : polygons) {
      for (std::size_t i = 1; i + 1 < polygon.size(); ++i) {
        ++read;
        const TriangleIndices t{static_cast<std::uint32_t>(polygon[0]),
                                static_cast<std::uint32_t>(polygon[i]),
                                static_cast<std::uint32_t>(polygon[i + 1])};
        if (CGAL::collinear(points[t[0]], points[t[1]], points[t[2]])) {
          ++degenerate;
        } else {
          expected.push_back(t);
        }
      }
    }
    EXPECT_EQ(soup.triangles, expected) << name;
    EXPECT_EQ(report.triangles_read, read) << name;
    EXPECT_EQ(report.degenerate_dropped, degenerate) << name;
    ++compared;
  }
  EXPECT_GT(compared, 0) << "no real mesh found under " << TETRAPAGE_MESH_DIR;
}

// read_mesh_in_chunks against read_mesh: CGAL's meshes written by CGAL in each format our
// readers read (binary STL and PLY, ASCII OBJ and OFF), a file with degenerate triangles and
// polygons, and PLY files with a part table (binary and ASCII, read in a pass of its own before
// the faces). The chunks, appended, are the whole read's triangles, parts and report; no chunk
// holds more than asked.
TEST(MeshReader, ChunksAppendedAreTheWholeRead) {
  using Point = CGAL::Exact_predicates_inexact_constructions_kernel::Point_3;
  const auto folder = scratch_folder("chunks");
  std::vector<std::filesystem::path> files;
  for (const char* name : {"elephant.off", "mech-holes-shark.off"}) {
    const auto path = std::filesystem::path(TETRAPAGE_MESH_DIR) / name;
    if (!std::filesystem::exists(path)) continue;
    std::vector<Point> points;
    std::vector<std::vector<std::size_t>> polygons;
    ASSERT_TRUE(CGAL::IO::read_polygon_soup(path.string(), points, polygons)) << name;
    for (const char* extension : {".obj", ".stl", ".ply", ".off"}) {
      files.push_back(folder / (path.stem().string() + extension));
      ASSERT_TRUE(CGAL::IO::write_polygon_soup(files.back().string(), points, polygons,
                                               CGAL::parameters::use_binary_mode(true)))
          << files.back();
    }
  }
  ASSERT_FALSE(files.empty()) << "no real mesh found under " << TETRAPAGE_MESH_DIR;
  // Degenerate triangles at the chunks' seams, a quad and a pentagon.
  files.push_back(folder / "degenerate.off");
  write_file(files.back(), "OFF\n7 6 0\n0 0 0\n1 0 0\n0 1 0\n2 2 2\n3 3 3\n0 0 0\n4 4 5\n"
                           "3 0 1 2\n3 0 1 1\n4 0 1 2 6\n3 0 3 4\n5 0 1 2 6 3\n3 0 5 1\n");
  TriangleSoup parts;
  parts.add_part("a");
  parts.add_part("b", "x/b");
  parts.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  parts.triangles = {{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}};
  parts.part_of = {0, 1, 1, 0};
  files.push_back(folder / "parts.ply");
  write_mesh(files.back(), parts);
  // An ASCII STL facet of five corners (its triangles span chunks, its corners shared by them).
  files.push_back(folder / "polygon.stl");
  write_file(files.back(), "solid p\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                           "vertex 1 1 0\nvertex 0.5 2 0\nvertex 0 1 0\nendloop\nendfacet\n"
                           "facet normal 0 0 1\nouter loop\nvertex 0 0 1\nvertex 1 0 1\n"
                           "vertex 1 1 1\nendloop\nendfacet\nendsolid p\n");
  // Faces before their vertices (PLY allows it), ASCII and binary, with a part table after the
  // faces: the vertices are read first, in a pass of their own.
  files.push_back(folder / "faces_first.ply");
  write_file(files.back(), "ply\nformat ascii 1.0\nelement face 2\n"
                           "property list uchar int vertex_indices\nelement vertex 4\n"
                           "property double x\nproperty double y\nproperty double z\nend_header\n"
                           "3 0 1 2\n3 0 2 3\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n");
  {
    // Binary: a quad, a degenerate triangle, a pentagon; two parts in a table after the faces.
    std::string bytes =
        "ply\nformat binary_little_endian 1.0\nelement face 4\n"
        "property list uchar int vertex_indices\nelement vertex 6\nproperty double x\n"
        "property double y\nproperty double z\nelement part 2\nproperty uint faces\n"
        "property list uint uchar name\nproperty list uint uchar path\nend_header\n";
    const auto put = [&bytes](const auto value) {
      bytes.append(reinterpret_cast<const char*>(&value), sizeof value);
    };
    for (const std::vector<std::int32_t>& face :
         std::vector<std::vector<std::int32_t>>{{0, 1, 2, 3}, {0, 0, 1}, {0, 1, 5}, {0, 1, 2, 4, 5}}) {
      put(std::uint8_t(face.size()));
      for (const std::int32_t corner : face) put(corner);
    }
    for (const double coordinate : {0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0., 0., 0., 1., 2., 2., 3.})
      put(coordinate);
    for (const auto& [faces, name] : {std::pair{3u, std::string("a")}, std::pair{1u, std::string("b")}}) {
      put(std::uint32_t(faces));
      put(std::uint32_t(name.size()));
      bytes += name;
      put(std::uint32_t(name.size()));
      bytes += name;
    }
    files.push_back(folder / "faces_first_binary.ply");
    write_file(files.back(), bytes);
  }
  // An ASCII part table: a part of no face, a quad, a part met again (parts need not be runs).
  files.push_back(folder / "table.ply");
  write_file(files.back(), "ply\nformat ascii 1.0\nelement vertex 5\nproperty double x\n"
                           "property double y\nproperty double z\nelement face 4\n"
                           "property list uchar int vertex_indices\nelement part 4\n"
                           "property uint faces\nproperty list uint uchar name\n"
                           "property list uint uchar path\nend_header\n"
                           "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n"
                           "3 0 1 4\n4 0 1 2 3\n3 1 2 4\n3 2 3 4\n"
                           "1 1 97 1 97\n0 1 98 1 98\n2 1 99 1 99\n1 1 97 3 97 35 50\n");

  for (const auto& file : files) {
    ReadReport whole_report;
    const TriangleSoup whole = read_mesh(file, &whole_report);
    // Chunks of 1, 3 and 1000 triangles; the vertex table beyond its first 37 vertices on disk,
    // read back through one block (the least cache), then held whole.
    for (const std::size_t size : {std::size_t(1), std::size_t(3), std::size_t(1000)}) {
      SCOPED_TRACE(file.filename().string() + ", chunks of " + std::to_string(size));
      test::HandedOver handed;
      SoupChunks chunks;
      chunks.triangles = size;
      if (size < 1000) {
        chunks.held_vertices = 37;
        chunks.vertex_folder = folder;
        chunks.vertex_cache_bytes = 1;
      }
      chunks.take = [&](TriangleSoup&& chunk) {
        // An STL facet's triangles share a chunk.
        const std::size_t most = file.filename() == "polygon.stl" ? size + 2 : size;
        EXPECT_LE(chunk.triangle_count(), most);
        EXPECT_EQ(chunk.part_of.size(), chunk.triangle_count());
        handed.add(chunk);
      };
      ReadReport report;
      const TriangleSoup names = read_mesh_in_chunks(file, &report, chunks);
      test::expect_whole_read(names, handed, whole);
      EXPECT_EQ(report.triangles_read, whole_report.triangles_read);
      EXPECT_EQ(report.degenerate_dropped, whole_report.degenerate_dropped);
      EXPECT_EQ(report.dropped_positions, whole_report.dropped_positions);
      EXPECT_EQ(report.polygons_triangulated, whole_report.polygons_triangulated);
      EXPECT_EQ(report.encoding, whole_report.encoding);
    }
  }
  for (const auto& entry : std::filesystem::directory_iterator(folder))
    EXPECT_EQ(entry.path().filename().string().find(".tetrapage-vertices"), std::string::npos);
}

// Debian's assimp-testmodels in the formats our readers read (binary and ASCII, float and
// double, polygons, files our readers refuse): read in chunks of 7 with the vertex table past
// 50 vertices on disk, each succeeds or fails as its whole read does, with the same triangles,
// parts and part names.
TEST(MeshReader, ForeignFilesReadInChunksAsWhole) {
  const std::filesystem::path models = "/usr/share/assimp/models";
  ASSERT_TRUE(std::filesystem::exists(models)) << "assimp-testmodels (make deps) holds them";
  const auto folder = scratch_folder("chunks_foreign");
  int read = 0, refused = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(models)) {
    std::string extension = entry.path().extension().string();
    for (char& c : extension) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (!entry.is_regular_file() ||
        (extension != ".ply" && extension != ".stl" && extension != ".obj" && extension != ".off"))
      continue;
    SCOPED_TRACE(entry.path().string());
    std::optional<TriangleSoup> whole;
    try {
      whole = read_mesh(entry.path());
    } catch (const Error&) {
    }
    std::vector<std::array<Vec3, 3>> corners;
    std::vector<std::uint32_t> part_of;
    SoupChunks chunks;
    chunks.triangles = 7;
    chunks.held_vertices = 50;
    chunks.vertex_folder = folder;
    chunks.take = [&](TriangleSoup&& chunk) {
      for (std::size_t t = 0; t < chunk.triangle_count(); ++t) {
        corners.push_back(chunk.corners(t));
        part_of.push_back(chunk.part_of[t]);
      }
    };
    std::optional<TriangleSoup> names;
    try {
      names = read_mesh_in_chunks(entry.path(), nullptr, chunks);
    } catch (const Error&) {
    }
    ASSERT_EQ(whole.has_value(), names.has_value());
    if (!whole) {
      ++refused;
      continue;
    }
    ++read;
    ASSERT_EQ(corners.size(), whole->triangle_count());
    for (std::size_t t = 0; t < corners.size(); ++t) {
      ASSERT_EQ(corners[t], whole->corners(t)) << "triangle " << t;
      ASSERT_EQ(part_of[t], whole->part_of[t]) << "triangle " << t;
    }
    EXPECT_EQ(names->part_names, whole->part_names);
    EXPECT_EQ(names->part_paths, whole->part_paths);
  }
  EXPECT_GT(read, 25);
  std::printf("%d foreign files read alike in chunks, %d refused by both\n", read, refused);
}

// A file whose triangles are all degenerate is refused in chunks as it is whole.
TEST(MeshReader, ChunksOfNothingAreRefusedAsTheWholeRead) {
  const auto path = scratch_folder("chunks_nothing") / "flat.off";
  write_file(path, "OFF\n3 2 0\n0 0 0\n1 1 1\n2 2 2\n3 0 1 2\n3 0 0 1\n");
  SoupChunks chunks;
  chunks.triangles = 1;
  chunks.take = [](TriangleSoup&&) { ADD_FAILURE() << "a degenerate triangle was handed over"; };
  expect_error<InputError>([&] { read_mesh_in_chunks(path, nullptr, chunks); },
                           {path.string(), "no triangle left", "2 degenerate"});
}

}  // namespace
}  // namespace tetrapage::test
