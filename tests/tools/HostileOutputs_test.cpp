// Outputs named indirectly: every file a command reads (the parts and sub-assemblies of a
// manifest, a glTF's buffers) is an input that no output may replace; a manifest's part folder
// is replaced only when it holds nothing but part files; a converted assembly keeps its unit;
// an output's temporary never outlives the run, whichever signal ends it.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "HostileSupport.h"
#include "tetrapage/formats/mesh/Pose.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;

using test::expect_refused;
using test::leftovers;
using test::read_file;
using test::run;
using HostileOutputs = test::HostileFolder;

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

TEST_F(HostileOutputs, FilesNamedInsideManifestsAreNeverOverwritten) {
  const std::string part = read_file(make_model("part.ply", 400));
  write_text(folder_ / "a.json", R"({"parts":[{"file":"part.ply"}]})");
  write_text(folder_ / "outer.json", R"({"parts":[{"name":"top","manifest":"top.json"}]})");
  write_text(folder_ / "top.json", R"({"parts":[{"file":"part.ply"}]})");
  const std::string top = read_file(folder_ / "top.json");
  // preprocess writes indexes only (.tpi): a mesh's or a manifest's name is a usage mistake.
  expect_refused(run(folder_, "preprocess a.json -o part.ply"), "part.ply", 2);
  expect_refused(run(folder_, "preprocess outer.json -o top.json"), "top.json", 2);
  expect_refused(run(folder_, "mesh convert a.json -o part.ply"), "which the input 'a.json' reads");
  expect_refused(run(folder_, "mesh convert outer.json -o ./top.json"), "which the input 'outer.json' reads");
  expect_refused(run(folder_, "mesh convert outer.json -o ./part.ply"), "part.ply");
  // An object given as a manifest: its part may not become the answers.
  ASSERT_EQ(run(folder_, "preprocess a.json -o model.tpi").status, 0);
  write_poses(folder_ / "flight.csv", std::vector<Pose>(3));
  write_text(folder_ / "object.json", R"({"parts":[{"file":"b.ply"}]})");
  ASSERT_EQ(run(folder_, "generate object --triangles 4 -o b.ply").status, 0);
  const std::string object = read_file(folder_ / "b.ply");
  expect_refused(
      run(folder_, "fly model.tpi --object object.json --path flight.csv --answers b.ply"),
      "b.ply");
  expect_refused(
      run(folder_, "fly model.tpi --object object.json --path flight.csv --report b.ply"), "b.ply");
  EXPECT_EQ(read_file(folder_ / "part.ply"), part);
  EXPECT_EQ(read_file(folder_ / "top.json"), top);
  EXPECT_EQ(read_file(folder_ / "b.ply"), object);
  EXPECT_TRUE(leftovers(folder_).empty());
}

// A glTF whose buffer is a file of its own (named like a mesh, as a user may have it).
TEST_F(HostileOutputs, AGltfsBufferIsAnInput) {
  float corners[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  {
    std::ofstream buffer(folder_ / "geometry.ply", std::ios::binary);
    buffer.write(reinterpret_cast<const char*>(corners), sizeof corners);
  }
  write_text(folder_ / "m.gltf", R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],
    "nodes":[{"mesh":0}],"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
    "buffers":[{"uri":"geometry.ply","byteLength":36}],
    "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36}],
    "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3",
                  "min":[0,0,0],"max":[1,1,0]}]})");
  ASSERT_EQ(run(folder_, "mesh info m.gltf").status, 0) << "the glTF must be readable";
  const std::string buffer = read_file(folder_ / "geometry.ply");
  expect_refused(run(folder_, "mesh convert m.gltf -o geometry.ply"),
                 "which the input 'm.gltf' reads");
  write_text(folder_ / "a.json", R"({"parts":[{"file":"m.gltf"}]})");
  expect_refused(run(folder_, "mesh convert a.json -o geometry.ply"), "geometry.ply");
  EXPECT_EQ(read_file(folder_ / "geometry.ply"), buffer);
  // A buffer that is a FIFO is refused at once, not waited on.
  fs::remove(folder_ / "geometry.ply");
  ASSERT_EQ(::mkfifo((folder_ / "geometry.ply").c_str(), 0600), 0);
  expect_refused(run(folder_, "mesh info m.gltf"), "FIFO");
}

// A foreign glTF 1.0 model (Debian's assimp-testmodels): its buffer, image and shaders are
// named in objects keyed by id, not arrays; every one is an input. With a damaged buffer Assimp
// aborts on an assertion: the read runs in a child, so the command says so in one line.
TEST_F(HostileOutputs, AForeignGltfOnesFilesAreInputsAndItsReaderCannotEndTheCommand) {
  const fs::path model = "/usr/share/assimp/models/glTF/BoxTextured-glTF";
  ASSERT_TRUE(fs::exists(model / "BoxTextured.gltf")) << "assimp-testmodels (make deps) holds it";
  fs::copy(model, folder_ / "box");
  write_text(folder_ / "box" / "a.json", R"({"parts":[{"file":"BoxTextured.gltf"}]})");
  const std::string buffer = read_file(folder_ / "box" / "BoxTextured.bin");
  make_model("model.ply", 400);
  ASSERT_EQ(run(folder_, "preprocess model.ply -o model.tpi").status, 0);
  write_poses(folder_ / "flight.csv", std::vector<Pose>(3));
  for (const char* output : {"box/BoxTextured.bin", "box/CesiumLogoFlat.png", "box/BoxTextured0FS.glsl"})
    expect_refused(run(folder_, std::string("fly model.tpi --object box/a.json --path flight.csv --report ") + output),
                   "which the input 'box/a.json' reads");
  EXPECT_EQ(read_file(folder_ / "box" / "BoxTextured.bin"), buffer);
  EXPECT_EQ(run(folder_, "mesh info box/BoxTextured.gltf").status, 0);
  // Its buffer replaced by text (what such an overwrite left): Assimp 5.2's glTF 1 importer
  // fails an assertion and aborts. The command used to end with SIGABRT; now the child does.
  std::string text = "{\n";
  for (int k = 0; k < 200; ++k) text += "  \"a\": 1,\n";
  write_text(folder_ / "box" / "BoxTextured.bin", text + "}\n");
  expect_refused(run(folder_, "mesh info box/BoxTextured.gltf"), "crashed Assimp");
}

// A manifest output replaces its part folder: only one that holds part files alone, and never
// one holding files the command reads.
TEST_F(HostileOutputs, AManifestsPartFolderIsReplacedOnlyWhenItIsItsOwn) {
  make_model("model.ply", 400);
  fs::create_directories(folder_ / "out.parts");
  write_text(folder_ / "out.parts" / "notes.txt", "mine");
  expect_refused(run(folder_, "mesh convert model.ply -o out.json"), "notes.txt");
  EXPECT_EQ(read_file(folder_ / "out.parts" / "notes.txt"), "mine");
  fs::remove(folder_ / "out.parts" / "notes.txt");
  ASSERT_EQ(run(folder_, "mesh convert model.ply -o out.json").status, 0);
  ASSERT_EQ(run(folder_, "mesh convert model.ply -o out.json").status, 0)
      << "its own folder is replaced";
  // An assembly whose parts live in the folder the output would replace.
  fs::rename(folder_ / "out.json", folder_ / "kept.json");
  const std::string kept = read_file(folder_ / "kept.json");
  expect_refused(run(folder_, "mesh convert kept.json -o out.json"), "out.parts");
  EXPECT_TRUE(fs::exists(folder_ / "out.parts" / "part-000000.ply"));
  EXPECT_EQ(run(folder_, "mesh info kept.json").status, 0);
  EXPECT_TRUE(leftovers(folder_).empty());
}

// A converted assembly states the unit it was in; preprocess then records it.
TEST_F(HostileOutputs, ConvertedAssembliesKeepTheirUnit) {
  make_model("part.ply", 400);
  for (const char* unit : {"m", "cm", "mm", "um", "in", "ft"}) {
    write_text(folder_ / "cell.json",
               std::string(R"({"units":")") + unit +
                   R"(","parts":[{"file":"part.ply","instances":[{"translation":[2,0,0]}]}]})");
    fs::create_directories(folder_ / "split");
    ASSERT_EQ(run(folder_, "mesh convert cell.json -o split/cell.json").status, 0) << unit;
    const auto written = nlohmann::json::parse(read_file(folder_ / "split" / "cell.json"));
    EXPECT_EQ(written["units"], unit);
    const test::CliResult built = run(folder_, "preprocess split/cell.json -o cell.tpi");
    ASSERT_EQ(built.status, 0) << built.err;
    const test::CliResult inspected = run(folder_, "inspect cell.tpi");
    EXPECT_NE(inspected.out.find(std::string("unit: ") + unit + "\n"), std::string::npos)
        << inspected.out;
    // The same placed coordinates as the original assembly.
    const test::CliResult original = run(folder_, "mesh info cell.json"),
                          converted = run(folder_, "mesh info split/cell.json");
    const auto bounds_line = [](const std::string& out) { return out.substr(out.find("bounds")); };
    ASSERT_NE(original.out.find("bounds"), std::string::npos) << original.out;
    EXPECT_EQ(bounds_line(original.out).substr(0, 80), bounds_line(converted.out).substr(0, 80))
        << unit;
  }
}

// mesh info reports the data's bounds, however far they lie (a model beyond the accepted
// coordinates is still described before preprocess refuses it).
TEST_F(HostileOutputs, MeshInfoBoundsAreTheDatas) {
  write_text(folder_ / "far.obj", "v -1e301 0 0\nv 1e308 1 0\nv 0 -2e305 3e302\nf 1 2 3\n");
  const test::CliResult info = run(folder_, "mesh info far.obj");
  ASSERT_EQ(info.status, 0) << info.err;
  EXPECT_NE(info.out.find("bounds [-1e+301, -2e+305, 0] .. [1e+308, 1, 3e+302]"), std::string::npos) << info.out;
}

// A reader of stdout that goes away (SIGPIPE) ends the flight without leaving a temporary, and
// a temporary left by a killed run is removed by the next run writing the same output.
TEST_F(HostileOutputs, TemporariesNeverOutliveTheRun) {
  make_model("model.ply", 400);
  ASSERT_EQ(run(folder_, "preprocess model.ply -o model.tpi").status, 0);
  ASSERT_EQ(run(folder_, "generate object --triangles 4 -o object.ply").status, 0);
  write_poses(folder_ / "flight.csv", std::vector<Pose>(2000));
  const std::string command = std::string(TETRAPAGE_CLI) +
                              " fly model.tpi --object object.ply --path flight.csv --answers a.csv"
                              " --contacts c.csv 2>/dev/null | head -c 1 >/dev/null";
  ASSERT_EQ(std::system(("cd '" + folder_.string() + "' && " + command).c_str()), 0);
  EXPECT_TRUE(leftovers(folder_).empty()) << leftovers(folder_)[0];
  // A stale temporary of a process that no longer exists.
  write_text(folder_ / "a.csv.tmp-999999999", "stale");
  ASSERT_EQ(
      run(folder_, "fly model.tpi --object object.ply --path flight.csv --answers a.csv").status,
      0);
  EXPECT_TRUE(leftovers(folder_).empty());
  EXPECT_TRUE(fs::exists(folder_ / "a.csv"));
}

}  // namespace
}  // namespace tetrapage
