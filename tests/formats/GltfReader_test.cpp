// Our glTF 2.0 reader against Assimp's (its own parser, its own node walk, float transforms) on
// the glTF files Debian's assimp-testmodels ship, read whole and in chunks; and the files it
// must refuse or hand to Assimp.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include <sys/stat.h>

#include "TestSupport.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/MeshWriter.h"

namespace tetrapage::test {
namespace {

namespace fs = std::filesystem;

const fs::path kGltfModels = "/usr/share/assimp/models/glTF2";

std::vector<fs::path> sample_gltf_files() {
  std::vector<fs::path> files;
  std::error_code error;
  if (!fs::is_directory(kGltfModels, error)) return files;
  for (const auto& entry : fs::recursive_directory_iterator(kGltfModels)) {
    const std::string extension = entry.path().extension().string();
    if (extension == ".gltf" || extension == ".glb") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

// The read, or the first words of why it failed.
struct Outcome {
  std::optional<TriangleSoup> soup;
  ReadReport report;
  std::string error;
};
template <class Read>
Outcome outcome_of(Read read) {
  Outcome out;
  try {
    out.soup = read(&out.report);
  } catch (const std::exception& e) {
    out.error = e.what();
  }
  return out;
}

// The corners of triangle t rotated to start at the smallest (a strip's or a fan's triangle may
// start at another corner in Assimp's order, keeping its orientation).
std::array<Vec3, 3> rotated_to_least(std::array<Vec3, 3> corners) {
  const auto least = std::min_element(corners.begin(), corners.end());
  std::rotate(corners.begin(), least, corners.end());
  return corners;
}

double largest_extent(const TriangleSoup& soup) {
  double extent = 0;
  for (const Vec3& p : soup.vertices)
    for (double c : p) extent = std::max(extent, std::abs(c));
  return extent;
}

// Assimp's soup and ours: the same triangles in the same order and parts, the corners equal to
// within Assimp's float transforms' rounding and its rotations taken as they are (we normalise
// a quaternion: Cameras.gltf's is 1.5e-6 off unit length), 1e-5 of the model's extent.
void expect_same_as_assimp(const TriangleSoup& ours, const TriangleSoup& theirs,
                           const std::string& name) {
  ASSERT_EQ(ours.triangle_count(), theirs.triangle_count()) << name;
  ASSERT_EQ(ours.part_count(), theirs.part_count()) << name;
  const double tolerance = 1e-5 * std::max(1.0, largest_extent(theirs));
  for (std::size_t t = 0; t < ours.triangle_count(); ++t) {
    ASSERT_EQ(ours.part_of[t], theirs.part_of[t]) << name << " triangle " << t;
    const auto a = rotated_to_least(ours.corners(t));
    const auto b = rotated_to_least(theirs.corners(t));
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c)
        ASSERT_NEAR(a[k][c], b[k][c], tolerance) << name << " triangle " << t << " corner " << k;
  }
}

// What our reader refuses that Assimp 5.2 reads (it silently drops or clamps the data), each
// with the reason named.
const std::map<std::string, std::string> kRefusedByUs = {
    {"IncorrectVertexArrays/Cube.gltf", "past its buffer's"},  // a view beyond its buffer
    {"IndexOutOfRange/IndexOutOfRange.gltf", "out of range"},  // Assimp drops those faces
};
// What Assimp refuses for what is no geometry (a material's or a scene name's type, a texture
// coordinate set's numbering): our reader reads them.
const std::set<std::string> kReadByUsAlone = {
    "issue_3269/texcoord_crash.gltf", "wrongTypes/badExtension.gltf", "wrongTypes/badNumber.gltf",
    "wrongTypes/badObject.gltf",      "wrongTypes/badString.gltf",    "wrongTypes/badUint.gltf"};

// One triangle's float corners (0,0,0), (1,0,0), (0,1,0), and with `indices` 0, 1, 2 as
// uint32 after them: 36 or 48 bytes.
void write_triangle_bin(const fs::path& path, bool indices = false) {
  Bytes bytes;
  for (float c : {0.0f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 0.0f, 1.0f, 0.0f}) bytes.put<float>(c);
  if (indices)
    for (std::uint32_t i : {0u, 1u, 2u}) bytes.put<std::uint32_t>(i);
  write_file(path, bytes.str());
}

// read_mesh(path) throws exactly E, whose message contains each of `parts`.
template <class E>
void expect_refused(const fs::path& path, const std::vector<std::string>& parts) {
  expect_error<E>([&] { read_mesh(path); }, parts);
}

// Read in chunks of 7 triangles, the vertex table past 11 vertices on disk.
void expect_chunks_are_the_whole_read(const fs::path& file, const TriangleSoup& whole) {
  HandedOver handed;
  SoupChunks chunks;
  chunks.triangles = 7;
  chunks.held_vertices = 11;
  chunks.vertex_cache_bytes = 1;
  chunks.take = [&](TriangleSoup&& chunk) {
    EXPECT_LE(chunk.triangle_count(), 7u);
    handed.add(chunk);
  };
  ReadReport report;
  const TriangleSoup names = read_mesh_in_chunks(file, &report, chunks);
  expect_whole_read(names, handed, whole);
}

// Every glTF of assimp-testmodels: read by us and by Assimp alike (the same triangles, parts
// and order; the corners within Assimp's float rounding), or refused alike, or one of the
// differences listed; our reads in chunks are our whole reads. Draco and glTF 1.0 techniques
// are Assimp's (report "assimp:gltf").
TEST(GltfReader, AssimpsSampleFilesReadAsAssimpReadsThem) {
  const std::vector<fs::path> files = sample_gltf_files();
  if (files.empty()) GTEST_SKIP() << "assimp-testmodels not installed (" << kGltfModels << ")";
  int compared = 0, own = 0;
  for (const fs::path& file : files) {
    const std::string name = file.lexically_relative(kGltfModels).string();
    const Outcome ours = outcome_of([&](ReadReport* r) { return read_mesh(file, r); });
    const Outcome theirs =
        outcome_of([&](ReadReport* r) { return read_mesh_with_assimp(file, r); });
    if (const auto refused = kRefusedByUs.find(name); refused != kRefusedByUs.end()) {
      ASSERT_TRUE(theirs.soup) << name << ": " << theirs.error;
      EXPECT_NE(ours.error.find(refused->second), std::string::npos) << name << ": " << ours.error;
      continue;
    }
    if (kReadByUsAlone.count(name) > 0) {
      ASSERT_TRUE(ours.soup) << name << ": " << ours.error;
      EXPECT_FALSE(theirs.soup) << name;
      EXPECT_GT(ours.soup->triangle_count(), 0u) << name;
      expect_chunks_are_the_whole_read(file, *ours.soup);
      continue;
    }
    ASSERT_EQ(ours.soup.has_value(), theirs.soup.has_value())
        << name << ": ours " << ours.error << " | Assimp's " << theirs.error;
    if (!ours.soup) continue;
    expect_same_as_assimp(*ours.soup, *theirs.soup, name);
    ++compared;
    if (ours.report.format.rfind("assimp:", 0) != 0) {
      ++own;
      EXPECT_EQ(ours.report.format, file.extension() == ".glb" ? "glb" : "gltf") << name;
      expect_chunks_are_the_whole_read(file, *ours.soup);
    }
  }
  // 2CylinderEngine (110k triangles, 4-level node transforms), ClearCoat, strips and fans...
  EXPECT_GE(own, 20);
  EXPECT_GE(compared, own + 2);  // the Draco and the techniqueWebGL files, through Assimp
}

// A mesh placed by many nodes: every placement is read, in chunks as whole, and the estimate
// counts the placed triangles from the JSON (not from the file's size, far smaller).
TEST(GltfReader, AMeshPlacedByManyNodesIsCountedAndReadPerPlacement) {
  const fs::path folder = scratch_folder("gltf_placed");
  const fs::path path = folder / "grid.gltf";
  Bytes buffer;
  for (float c : {0.0f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 0.0f, 1.0f, 0.0f, 1.0f, 1.0f, 0.0f})
    buffer.put<float>(c);
  for (std::uint16_t i : {0, 1, 2, 1, 3, 2}) buffer.put<std::uint16_t>(i);
  write_file(folder / "grid.bin", buffer.str());
  constexpr int kNodes = 500;
  std::string nodes, roots;
  for (int n = 0; n < kNodes; ++n) {
    nodes += std::string(n ? "," : "") + R"({"mesh": 0, "translation": [)" + std::to_string(2 * n) +
             ", 0, 0]}";
    roots += std::string(n ? "," : "") + std::to_string(n);
  }
  write_file(path,
             R"({"asset": {"version": "2.0"}, "scenes": [{"nodes": [)" + roots +
                 R"(]}], "nodes": [)" + nodes +
                 R"(], "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"},
                  {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}],
    "bufferViews": [{"buffer": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 12}],
    "buffers": [{"uri": "grid.bin", "byteLength": 60}]})");
  const MeshReadEstimate estimate = estimate_mesh_read(path);
  EXPECT_TRUE(estimate.counted);
  EXPECT_TRUE(estimate.chunked);
  EXPECT_EQ(estimate.triangles, 2u * kNodes);
  EXPECT_EQ(estimate.vertices, 4u * kNodes);
  const TriangleSoup soup = read_mesh(path);
  ASSERT_EQ(soup.triangle_count(), 2u * kNodes);
  ASSERT_EQ(soup.part_count(), std::size_t(kNodes));
  for (std::size_t t = 0; t < soup.triangle_count(); ++t) {
    const double x = 2.0 * double(soup.part_of[t]);
    const auto corners = soup.corners(t);
    EXPECT_EQ(corners[0], (t % 2 == 0 ? Vec3{x, 0, 0} : Vec3{x + 1, 0, 0})) << t;
  }
  EXPECT_EQ(soup.part_names[0], "grid/node0");
  expect_chunks_are_the_whole_read(path, soup);
}

// Each malformed file gets one line naming the file and the object at fault, and no read of
// memory outside the file (the fuzz target covers the rest).
TEST(GltfReader, MalformedFilesAreRefusedNamingWhatIsWrong) {
  const fs::path folder = scratch_folder("gltf_malformed");
  write_triangle_bin(folder / "t.bin", true);
  const auto gltf =
      [&](const std::string& name, const std::string& nodes, const std::string& accessors,
          const std::string& views =
              R"([{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 12}])",
          const std::string& buffers = R"([{"uri": "t.bin", "byteLength": 48}])") {
        const fs::path path = folder / name;
        write_file(
            path,
            R"({"asset": {"version": "2.0"}, "nodes": )" + nodes +
                R"(, "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}], "accessors": )" +
                accessors + R"(, "bufferViews": )" + views + R"(, "buffers": )" + buffers + "}");
        return path;
      };
  const std::string one_node = R"([{"mesh": 0}])";
  const std::string good_accessors =
      R"([{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}, {"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"}])";
  // The good file reads (what each case below breaks).
  EXPECT_EQ(read_mesh(gltf("good.gltf", one_node, good_accessors)).triangle_count(), 1u);
  expect_refused<FormatError>(
      gltf(
          "past_view.gltf", one_node,
          R"([{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"}, {"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"}])"),
      {"past_view.gltf", "accessor 0", "pass the end of its bufferView"});
  // 2^62 indices of 4 bytes: the product wraps 64 bits.
  expect_refused<FormatError>(
      gltf(
          "wraps.gltf", one_node,
          R"([{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}, {"bufferView": 1, "componentType": 5125, "count": 4611686018427387904, "type": "SCALAR"}])"),
      {"wraps.gltf", "accessor 1", "pass the end of its bufferView"});
  expect_refused<FormatError>(
      gltf("cycle.gltf", R"([{"mesh": 0, "children": [1]}, {"children": [1]}])", good_accessors),
      {"cycle.gltf", "node 1", "reached twice"});
  expect_refused<FormatError>(
      gltf("child.gltf", R"([{"mesh": 0, "children": [7]}])", good_accessors),
      {"child.gltf", "node 0", "child 7 out of range"});
  expect_refused<InputError>(
      gltf(
          "index.gltf", one_node,
          R"([{"bufferView": 0, "componentType": 5126, "count": 2, "type": "VEC3"}, {"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"}])"),
      {"index.gltf", "accessor 1", "is 2, out of range (2 vertices)"});
  expect_refused<FormatError>(
      gltf("short_buffer.gltf", one_node, good_accessors, R"([{"buffer": 0, "byteLength": 36}])",
           R"([{"uri": "t.bin", "byteLength": 4800}])"),
      {"short_buffer.gltf", "buffer 0", "holds 48"});
  expect_refused<FormatError>(
      gltf("not_base64.gltf", one_node, good_accessors, R"([{"buffer": 0, "byteLength": 36}])",
           R"([{"uri": "data:application/octet-stream;base64,AA*A", "byteLength": 3}])"),
      {"not_base64.gltf", "buffer 0", "not base64"});
  expect_refused<FormatError>(
      gltf(
          "quantized.gltf", one_node,
          R"([{"bufferView": 0, "componentType": 5123, "count": 3, "type": "VEC3"}, {"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"}])"),
      {"quantized.gltf", "accessor 0", "POSITION is not VEC3 of floats"});
  // A buffer named by a FIFO would block a reader forever.
  const fs::path fifo = folder / "fifo.bin";
  fs::remove(fifo);
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  expect_refused<IoError>(
      gltf("fifo.gltf", one_node, good_accessors, R"([{"buffer": 0, "byteLength": 36}])",
           R"([{"uri": "fifo.bin", "byteLength": 36}])"),
      {"fifo.bin"});
  // A GLB whose chunk states more bytes than the file has.
  Bytes glb;
  glb.text("glTF")
      .put<std::uint32_t>(2)
      .put<std::uint32_t>(32)
      .put<std::uint32_t>(1000)
      .text("JSON")
      .text("{}          ");
  write_file(folder / "long_chunk.glb", glb.str());
  expect_refused<FormatError>(folder / "long_chunk.glb", {"long_chunk.glb", "chunk 0"});
}

// What a hostile file's counts cannot make the reader do: allocate by a count its bytes do not
// back (100k views of one 1 MiB file, an accessor of 10^15 elements: checked against its view
// before anything is reserved), copy a mesh's primitives per node (2,000 nodes of a mesh with
// 2,000 empty primitives), or read a buffer outside the model's folder by an absolute path.
TEST(GltfReader, CountsAFileStatesAreCheckedBeforeTheyCostMemory) {
  const fs::path folder = scratch_folder("gltf_counts");
  write_file(folder / "a.bin", std::string(1 << 20, '\0'));
  std::string buffers;
  for (int b = 0; b < 20'000; ++b)
    buffers += std::string(b ? "," : "") + R"({"uri": "a.bin", "byteLength": 1048576})";
  write_file(folder / "alias.gltf", R"({"asset": {"version": "2.0"}, "nodes": [{"mesh": 0}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 1000000000000000, "type": "VEC3"}],
    "bufferViews": [{"buffer": 0, "byteLength": 36}], "buffers": [)" +
                                        buffers + "]}");
  expect_refused<FormatError>(folder / "alias.gltf", {"alias.gltf", "accessor 0", "pass the end"});

  std::string nodes, primitives;
  for (int n = 0; n < 2'000; ++n) {
    nodes += std::string(n ? "," : "") + R"({"mesh": 0})";
    primitives += std::string(n ? "," : "") + R"({"attributes": {"POSITION": 1}})";
  }
  write_triangle_bin(folder / "t.bin");
  write_file(folder / "amplify.gltf", R"({"asset": {"version": "2.0"}, "nodes": [)" + nodes + R"(],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}, )" +
                                          primitives + R"(]}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
                  {"bufferView": 0, "componentType": 5126, "count": 0, "type": "VEC3"}],
    "bufferViews": [{"buffer": 0, "byteLength": 36}], "buffers": [{"uri": "t.bin", "byteLength": 36}]})");
  const MeshReadEstimate estimate = estimate_mesh_read(folder / "amplify.gltf");
  EXPECT_TRUE(estimate.counted);
  EXPECT_EQ(estimate.triangles, 2'000u);
  EXPECT_LT(estimate.reading_bytes, std::uint64_t(64) << 20);  // 4M copied primitives: 128 MiB
  EXPECT_EQ(read_mesh(folder / "amplify.gltf").triangle_count(), 2'000u);

  write_file(folder / "absolute.gltf", R"({"asset": {"version": "2.0"}, "nodes": [{"mesh": 0}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}],
    "bufferViews": [{"buffer": 0, "byteLength": 36}], "buffers": [{"uri": ")" +
                                           (folder / "t.bin").string() +
                                           R"(", "byteLength": 36}]})");
  expect_refused<FormatError>(folder / "absolute.gltf",
                              {"absolute.gltf", "buffer 0", "an absolute path"});
}

// A rotation is a unit quaternion by the format; one of another length is normalised (it only
// rotates), and one of length zero is refused. A GLB's chunk of an unknown type before its BIN
// chunk is skipped.
TEST(GltfReader, RotationsAreNormalisedAndUnknownChunksSkipped) {
  const fs::path folder = scratch_folder("gltf_rotation");
  write_triangle_bin(folder / "t.bin");
  const auto rotated = [&](const std::string& name, const std::string& rotation) {
    write_file(
        folder / name,
        R"({"asset": {"version": "2.0"}, "nodes": [{"mesh": 0, "rotation": )" + rotation + R"(}],
      "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
      "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}],
      "bufferViews": [{"buffer": 0, "byteLength": 36}], "buffers": [{"uri": "t.bin", "byteLength": 36}]})");
    return folder / name;
  };
  // Half a turn about z, at twice unit length.
  const TriangleSoup turned = read_mesh(rotated("turned.gltf", "[0, 0, 2, 0]"));
  ASSERT_EQ(turned.triangle_count(), 1u);
  EXPECT_EQ(turned.corners(0)[1], (Vec3{-1, 0, 0}));
  EXPECT_EQ(turned.corners(0)[2], (Vec3{0, -1, 0}));
  expect_refused<FormatError>(rotated("zero.gltf", "[0, 0, 0, 0]"),
                              {"zero.gltf", "node 0", "rotation"});

  // A GLB: the JSON, a 1 MiB chunk of type "XTRA", then the BIN chunk.
  const std::string json =
      R"({"asset": {"version": "2.0"}, "nodes": [{"mesh": 0}], "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}], "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}], "bufferViews": [{"buffer": 0, "byteLength": 36}], "buffers": [{"byteLength": 36}]})";
  const std::string padded = json + std::string((4 - json.size() % 4) % 4, ' ');
  const std::string extra(1 << 20, 'x');
  Bytes glb;
  glb.text("glTF").put<std::uint32_t>(2).put<std::uint32_t>(
      std::uint32_t(12 + 8 + padded.size() + 8 + extra.size() + 8 + 36));
  glb.put<std::uint32_t>(std::uint32_t(padded.size())).text("JSON").text(padded);
  glb.put<std::uint32_t>(std::uint32_t(extra.size())).text("XTRA").text(extra);
  glb.put<std::uint32_t>(36).text(std::string_view("BIN\0", 4)).text(read_file(folder / "t.bin"));
  write_file(folder / "extra.glb", glb.str());
  const TriangleSoup soup = read_mesh(folder / "extra.glb");
  ASSERT_EQ(soup.triangle_count(), 1u);
  EXPECT_EQ(soup.corners(0)[1], (Vec3{1, 0, 0}));
}

// Files our reader leaves to Assimp: glTF 1.0, and an extension that changes the geometry.
TEST(GltfReader, WhatItDoesNotReadGoesToAssimp) {
  const fs::path folder = scratch_folder("gltf_assimp");
  write_triangle_bin(folder / "t.bin");
  const std::string rest = R"(, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}],
    "bufferViews": [{"buffer": 0, "byteLength": 36}], "buffers": [{"uri": "t.bin", "byteLength": 36}]})";
  write_file(folder / "plain.gltf", R"({"asset": {"version": "2.0"})" + rest);
  write_file(
      folder / "materials.gltf",
      R"({"asset": {"version": "2.0"}, "extensionsRequired": ["KHR_materials_unlit"])" + rest);
  write_file(
      folder / "instancing.gltf",
      R"({"asset": {"version": "2.0"}, "extensionsRequired": ["EXT_mesh_gpu_instancing"])" + rest);
  ReadReport report;
  EXPECT_EQ(read_mesh(folder / "plain.gltf", &report).triangle_count(), 1u);
  EXPECT_EQ(report.format, "gltf");
  EXPECT_EQ(read_mesh(folder / "materials.gltf", &report).triangle_count(), 1u);
  EXPECT_EQ(report.format, "gltf");
  // Assimp 5.2 reads what it can of it (or refuses it): ours never guesses at an instancing.
  try {
    read_mesh(folder / "instancing.gltf", &report);
  } catch (const Error&) {
  }
  EXPECT_EQ(report.format, "assimp:gltf");
  EXPECT_FALSE(estimate_mesh_read(folder / "instancing.gltf").chunked);
}

}  // namespace
}  // namespace tetrapage::test
