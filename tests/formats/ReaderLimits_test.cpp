// Hostile text and mesh files: counts that a few bytes can announce (2^32 - 1 faces, a list
// of 2^32 - 1 corners) must be rejected from the file's size before anything is sized by them,
// naming the file, the element and the value; each case runs in a child whose address space is
// capped, so that a reader allocating gigabytes fails here even where memory is overcommitted.
// Deeply nested manifests are rejected by their depth, before their value is ever printed.

#include <string>

#include "../MemoryLimit.h"
#include "TestSupport.h"
#include "tetrapage/formats/mesh/Manifest.h"
#include "tetrapage/formats/mesh/Pose.h"

namespace tetrapage::test {
namespace {

/// `action` must throw exactly `kind` ("FormatError", ...) in a memory-capped child, with a
/// message holding every one of `parts`.
void expect_capped_error(const std::string& kind, const std::function<void()>& action,
                         const std::vector<std::string>& parts) {
  const ChildOutcome outcome = run_with_memory_limit(action);
  EXPECT_EQ(outcome.kind, kind) << outcome.message;
  for (const auto& part : parts)
    EXPECT_NE(outcome.message.find(part), std::string::npos)
        << "message '" << outcome.message << "' does not contain '" << part << "'";
  EXPECT_EQ(outcome.message.find('\n'), std::string::npos) << "not one line: " << outcome.message;
}

std::string ply_header(const std::string& encoding, std::uint64_t vertices, std::uint64_t faces,
                       const std::string& count_type = "uchar") {
  return "ply\nformat " + encoding + " 1.0\nelement vertex " + std::to_string(vertices) +
         "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
         std::to_string(faces) + "\nproperty list " + count_type + " int vertex_indices\nend_header\n";
}

std::string binary_triangle() {
  Bytes bytes;
  for (float c : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) bytes.put(c);
  return bytes.str();
}

TEST(ReaderLimits, PlyFaceCountOfTwoToThe32IsRejectedByTheFileSize) {
  const auto folder = scratch_folder("ply_counts");
  const auto path = folder / "faces.ply";
  // 2^32 - 1 faces in a file of about 300 bytes.
  Bytes face;
  face.put(std::uint8_t{3}).put(std::int32_t{0}).put(std::int32_t{1}).put(std::int32_t{2});
  write_file(path, ply_header("binary_little_endian", 3, 0xffffffffu) + binary_triangle() + face.str());
  expect_capped_error("FormatError", [&] { read_mesh(path); },
                      {path.string(), "element 'face'", "4294967295", "bytes"});
  write_file(path, ply_header("ascii", 3, 0xffffffffu) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  expect_capped_error("FormatError", [&] { read_mesh(path); },
                      {path.string(), "element 'face'", "4294967295"});
  write_file(path, ply_header("binary_big_endian", 0xffffffffu, 1) + binary_triangle());
  expect_capped_error("FormatError", [&] { read_mesh(path); },
                      {path.string(), "element 'vertex'", "4294967295"});
  // Counts up to 2^64 - 1 do not wrap around the check.
  write_file(path, ply_header("binary_little_endian", 3, 0xffffffffffffffffu) + binary_triangle());
  expect_capped_error("FormatError", [&] { read_mesh(path); },
                      {path.string(), "element 'face'", "18446744073709551615"});
}

TEST(ReaderLimits, PlyListCountBeyondTheFileIsRejectedBeforeReading) {
  const auto folder = scratch_folder("ply_lists");
  const auto path = folder / "corners.ply";
  Bytes face;
  face.put(std::uint32_t{0xffffffffu}).put(std::int32_t{0}).put(std::int32_t{1}).put(std::int32_t{2});
  write_file(path, ply_header("binary_little_endian", 3, 1, "uint") + binary_triangle() + face.str());
  expect_capped_error("FormatError", [&] { read_mesh(path); },
                      {path.string(), "face 0", "'vertex_indices'", "4294967295 items"});
  write_file(path, ply_header("ascii", 3, 1, "uint") + "0 0 0\n1 0 0\n0 1 0\n4294967295 0 1 2\n");
  expect_capped_error("FormatError", [&] { read_mesh(path); },
                      {path.string(), "face 0", "'vertex_indices'", "4294967295 items"});
  // The last list of a file, without a final newline, still reads.
  write_file(path, ply_header("ascii", 3, 1, "uint") + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2");
  EXPECT_EQ(read_mesh(path).triangle_count(), 1u);
}

TEST(ReaderLimits, PlyElementsWithoutPropertiesAreSkippedWhateverTheirCount) {
  const auto folder = scratch_folder("ply_empty_elements");
  const auto path = folder / "empty.ply";
  for (const std::string encoding : {"ascii", "binary_little_endian"}) {
    std::string header = ply_header(encoding, 3, 1);
    header.insert(header.find("end_header"), "element nothing 18446744073709551615\n");
    write_file(path, header + (encoding == "ascii" ? std::string("0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
                                                    : binary_triangle() + Bytes()
                                                                             .put(std::uint8_t{3})
                                                                             .put(std::int32_t{0})
                                                                             .put(std::int32_t{1})
                                                                             .put(std::int32_t{2})
                                                                             .str()));
    EXPECT_EQ(read_mesh(path).triangle_count(), 1u) << encoding;
  }
}

TEST(ReaderLimits, OffCountsBeyondTheFileAreRejected) {
  const auto folder = scratch_folder("off_counts");
  const auto path = folder / "big.off";
  write_file(path, "OFF\n3 4294967295 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  expect_capped_error("FormatError", [&] { read_mesh(path); },
                      {path.string(), "line 2", "4294967295 faces", "bytes"});
  write_file(path, "OFF\n4294967295 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  expect_capped_error("FormatError", [&] { read_mesh(path); },
                      {path.string(), "line 2", "4294967295 vertices", "bytes"});
  write_file(path, "OFF\n18446744073709551615 18446744073709551615 0\n0 0 0\n");
  expect_capped_error("FormatError", [&] { read_mesh(path); },
                      {path.string(), "18446744073709551615 vertices"});
  // Exactly enough: the shortest lines, the last without its newline.
  write_file(path, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2");
  EXPECT_EQ(read_mesh(path).triangle_count(), 1u);
}

TEST(ReaderLimits, StlAndObjNeverSizeAnythingByAClaim) {
  const auto folder = scratch_folder("stl_obj");
  // A binary STL header announcing 2^32 - 1 triangles in 134 bytes.
  const auto stl = folder / "big.stl";
  std::string bytes(80, '\0');
  bytes += Bytes().put(std::uint32_t{0xffffffffu}).str() + std::string(50, '\0');
  write_file(stl, bytes);
  expect_capped_error("FormatError", [&] { read_mesh(stl); }, {stl.string(), "4294967295 triangles"});
  // An OBJ line of a megabyte and a face of 10^5 corners read as they are.
  const auto obj = folder / "long.obj";
  std::string text = "v 0 0 0\nv 1 0 0\nv 0 1 0\n# " + std::string(1 << 20, 'x') + "\nf";
  for (int k = 0; k < 100000; ++k) text += k % 2 == 0 ? " 1" : " 2";
  write_file(obj, text + " 3\n");
  expect_capped_error("returned", [&] { read_mesh(obj); }, {});
}

// A line with no end (a binary file given a text format's name) fails at the line limit, under
// a memory cap, instead of growing the line buffer with the file.
TEST(ReaderLimits, EndlessLinesFailAtTheLineLimit) {
  const auto folder = scratch_folder("endless");
  const auto obj = folder / "endless.obj";
  write_file(obj, "v 0 0 0\n# " + std::string(70u << 20, 'x'));
  expect_capped_error("FormatError", [&] { read_mesh(obj); }, {obj.string(), "line 2 is longer than 64 MiB"});
  const auto poses = folder / "endless.csv";
  write_file(poses, "tx,ty,tz,qw,qx,qy,qz\n" + std::string(70u << 20, '1'));
  expect_capped_error("FormatError", [&] { read_poses(poses); }, {poses.string(), "longer than"});
}

TEST(ReaderLimits, DeeplyNestedManifestIsRejectedByItsDepth) {
  const auto folder = scratch_folder("manifest_depth");
  const auto path = folder / "deep.json";
  // 50,000 levels: printing this value (or destroying it recursively) overflowed the stack.
  constexpr int depth = 50000;
  write_file(path, "{\"units\": " + std::string(depth, '[') + std::string(depth, ']') + "}");
  expect_capped_error("FormatError", [&] { read_manifest(path); },
                      {path.string(), "nested deeper than 64"});
  // Deep enough to be refused, shallow enough to show the message is short.
  write_file(path, "{\"parts\": [{\"file\": \"a.ply\", \"instances\": " + std::string(70, '[') +
                       std::string(70, ']') + "}]}");
  expect_capped_error("FormatError", [&] { read_manifest(path); }, {path.string(), "depth 65"});
  // A large but flat value is summarised, not printed whole.
  std::string wide = "{\"units\": [";
  for (int i = 0; i < 200000; ++i) wide += i == 0 ? "1" : ",1";
  write_file(path, wide + "]}");
  const ChildOutcome outcome = run_with_memory_limit([&] { read_manifest(path); });
  EXPECT_EQ(outcome.kind, "FormatError") << outcome.message;
  EXPECT_NE(outcome.message.find("units"), std::string::npos) << outcome.message;
  EXPECT_LT(outcome.message.size(), 300u) << outcome.message;
}

// Found by fuzz_manifest: a number beyond double's range made nlohmann-json throw its
// out_of_range, which escaped read_manifest as no tetrapage::Error.
TEST(ReaderLimits, ManifestNumberBeyondDoubleIsAFormatError) {
  const auto folder = scratch_folder("manifest_number");
  const auto path = folder / "big.json";
  write_file(path, "2522222222222222222222222222222222222222222E22222222222222222222222222222222222222");
  test::expect_error<FormatError>([&] { read_manifest(path); }, {path.string(), "not valid JSON", "overflow"});
  write_file(path, "{\"parts\": [{\"file\": \"a.ply\", \"instances\": [{\"scale\": 1e999}]}]}");
  test::expect_error<FormatError>([&] { read_manifest(path); }, {path.string(), "not valid JSON", "1e999"});
}

// Found by fuzz_manifest: a string value cut for the message inside a two-byte character,
// which nlohmann-json's dump() then refused (type_error 316, no tetrapage::Error).
TEST(ReaderLimits, ManifestMessagesCutStringsBetweenCharactersAndStayOneLine) {
  const auto folder = scratch_folder("manifest_strings");
  const auto path = folder / "strings.json";
  std::string name = "x";  // then 'v' and a two-byte character: byte 57 is inside one
  for (int i = 0; i < 40; ++i) name += "v\u02e0";
  write_file(path, "\"" + name + "\"");
  test::expect_error<FormatError>([&] { read_manifest(path); }, {path.string(), "top level", "expected an object"});
  // Names quoted in messages keep them on one line.
  write_file(path, "{\"units\": \"furlong\\nper fortnight\", \"parts\": [{\"file\": \"a.ply\"}]}");
  test::expect_error<InputError>([&] { read_manifest(path); }, {path.string(), "'furlong\\nper fortnight'"});
  write_file(path, "{\"parts\": [{\"file\": \"a.ply\", \"bad\\nfield\": 1}]}");
  test::expect_error<FormatError>([&] { read_manifest(path); }, {path.string(), "'bad\\nfield'"});
}

}  // namespace
}  // namespace tetrapage::test
