// --memory is a cap: a file placed thousands of times and one large file each stay within the
// budget + the process's own memory before any work + kPreprocessInputAllowance, measured in
// a child process; a model whose tables or placed triangles cannot fit is refused up front
// with the figure; and placing copies in batches stores the same triangles, ids and parts.

#include <BRepPrimAPI_MakeSphere.hxx>
#include <STEPCAFControl_Writer.hxx>
#include <TDataStd_Name.hxx>
#include <TDocStd_Document.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <fstream>
#include <string>

#include "../ResidentMemory.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/MemoryUsage.h"
#include "tetrapage/formats/index/IndexReader.h"
#include "tetrapage/formats/mesh/Manifest.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/preprocess/Preprocess.h"
#include "tetrapage/runtime/paging/Shard.h"
#include "tetrapage/tools/IndexAudit.h"
#include "tetrapage/tools/TerrainGenerator.h"
#include "tetrapage/tools/TetrasGenerator.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;

fs::path test_folder(const std::string& name) {
  const fs::path folder = fs::path(TETRAPAGE_TEST_TMP) / "preprocess-memory" / name;
  fs::remove_all(folder);
  fs::create_directories(folder);
  return folder;
}

// A part of `triangles` random tetrahedra's faces (a component each).
fs::path make_tetras_part(const fs::path& folder, std::uint64_t triangles) {
  const fs::path path = folder / "tetras.ply";
  TetrasOptions options;
  options.triangles = triangles;
  MeshWriter writer(path);
  generate_tetras(options, writer);
  writer.commit();
  return path;
}

// A terrain of about `triangles` (one component).
fs::path make_terrain(const fs::path& path, std::uint64_t triangles) {
  TerrainOptions options;
  options.triangles = triangles;
  MeshWriter writer(path);
  generate_terrain(options, writer);
  writer.commit();
  return path;
}

// A manifest placing `file` `outer` x `inner` times (a sub-assembly of `inner` copies, placed
// `outer` times), each copy in its own unit cube.
fs::path make_manifest(const fs::path& folder, const fs::path& file, std::size_t outer,
                       std::size_t inner) {
  nlohmann::json copies = nlohmann::json::array(), blocks = nlohmann::json::array();
  for (std::size_t i = 0; i < inner; ++i)
    copies.push_back({{"translation", {double(i % 100), double(i / 100), 0.0}}});
  for (std::size_t i = 0; i < outer; ++i)
    blocks.push_back({{"translation", {0.0, 0.0, double(i)}}});
  std::ofstream(folder / "block.json")
      << nlohmann::json{{"parts", {{{"file", file.filename().string()}, {"instances", copies}}}}};
  const fs::path path = folder / "model.json";
  std::ofstream(path) << nlohmann::json{
      {"parts", {{{"name", "block"}, {"manifest", "block.json"}, {"instances", blocks}}}}};
  return path;
}

// The InputError message of a preprocess that must be refused ("", and a failure, if it ran).
std::string refusal(const std::vector<fs::path>& inputs, const fs::path& output,
                    const PreprocessOptions& options) {
  try {
    preprocess(inputs, output, options);
  } catch (const InputError& error) {
    return error.what();
  }
  ADD_FAILURE() << "not refused";
  return {};
}

struct ChildRun {
  int status = -1;
  std::uint64_t max_rss_bytes = 0;  // the child's ru_maxrss
  // This process's resident memory when it forked: the child's ru_maxrss counts the copy it
  // was before it ran the command (a test binary run whole has grown by earlier tests).
  std::uint64_t parent_rss_bytes = 0;
  nlohmann::json report;
};

// Runs `tetrapage preprocess INPUT -o OUTPUT --memory MEMORY --report` in a child process. Its
// ru_maxrss covers only the run's last stretch (the stages reset VmHWM through clear_refs,
// which the kernel's ru_maxrss follows), so the report's peak, VmHWM kept across the resets
// from the start of the run, is the figure checked; ru_maxrss is checked too.
ChildRun run_preprocess(const fs::path& input, const fs::path& output, const char* memory) {
  const fs::path report = output.string() + ".json";
  const std::uint64_t parent_rss = resident_bytes();
  const pid_t child = fork();
  if (child == 0) {
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, 1);
    ::dup2(null, 2);
    ::execl(TETRAPAGE_CLI, "tetrapage", "preprocess", input.c_str(), "-o", output.c_str(),
            "--memory", memory, "--report", report.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ChildRun run;
  run.parent_rss_bytes = parent_rss;
  rusage usage{};
  ::wait4(child, &run.status, 0, &usage);
  run.max_rss_bytes = std::uint64_t(usage.ru_maxrss) * 1024;
  std::ifstream in(report);
  if (in) run.report = nlohmann::json::parse(in);
  return run;
}

// `reads_in_a_child`: the command reads its input in a child process of its own (STEP, IGES,
// the formats Assimp reads), whose memory wait4's ru_maxrss counts and the promise does not.
void expect_within_promise(const ChildRun& run, std::uint64_t memory, bool reads_in_a_child = false) {
  ASSERT_EQ(run.status, 0);
  const auto peak = run.report.at("peak_rss_bytes").get<std::uint64_t>();
  const auto start = run.report.at("resident_at_start_bytes").get<std::uint64_t>();
  const std::uint64_t promise = memory + start + kPreprocessInputAllowance;
  EXPECT_EQ(run.report.at("promised_peak_bytes").get<std::uint64_t>(), promise);
  if (!test::kResidentMemoryIsTheProgramsOwn) return;
  EXPECT_LE(peak, promise) << run.report.dump(2);
  if (reads_in_a_child) return;
  if (run.max_rss_bytes <= run.parent_rss_bytes) return;  // the fork's copy, not the command
  EXPECT_LE(run.max_rss_bytes, promise);
  EXPECT_GE(peak, run.max_rss_bytes);
}

// On 25b82ee the 2,000 copies were placed into one soup: the ingest peaked far above.
TEST(PreprocessMemory, AFilePlacedThousandsOfTimesStaysWithinTheBudget) {
  const fs::path folder = test_folder("instances");
  const fs::path manifest = make_manifest(folder, make_terrain(folder / "part.ply", 1000), 20, 100);
  const ChildRun run = run_preprocess(manifest, folder / "model.tpi", "16M");
  expect_within_promise(run, std::uint64_t(16) << 20);
  EXPECT_EQ(run.report.at("triangles_read").get<std::uint64_t>(),
            2000 * read_mesh(folder / "part.ply").triangle_count());
  EXPECT_EQ(run.report.at("parts").get<std::uint64_t>(), 2000u);
}

// On 25b82ee a 1M-triangle PLY peaked at 137 MiB under 16M (its soup, a second copy while
// appended, and a centroid a triangle): above 16M + 48 + 64 MiB.
TEST(PreprocessMemory, AMillionTrianglePlyStaysWithinTheBudget) {
  const fs::path folder = test_folder("terrain");
  const fs::path input = make_terrain(folder / "terrain.ply", 1'000'000);
  const ChildRun run = run_preprocess(input, folder / "terrain.tpi", "16M");
  expect_within_promise(run, std::uint64_t(16) << 20);
}

// 10^6 parts' tables alone exceed a quarter of 16M: refused before any file is read.
TEST(PreprocessMemory, TablesBeyondTheBudgetAreRefusedUpFront) {
  const fs::path folder = test_folder("tables");
  const fs::path manifest = make_manifest(folder, make_tetras_part(folder, 4), 1000, 1000);
  PreprocessOptions options;
  options.memory_bytes = std::uint64_t(16) << 20;
  const std::string message = refusal({manifest}, folder / "model.tpi", options);
  EXPECT_NE(message.find("1000000 parts need about 68.7 MiB"), std::string::npos) << message;
  EXPECT_NE(message.find("--memory 16.0 MiB"), std::string::npos) << message;
  EXPECT_FALSE(fs::exists(folder / "model.tpi"));
}

// "raise --memory to 120.0 MiB or more": the figure as a --memory argument ("120M").
std::string raised_memory(const std::string& message) {
  const std::string key = "raise --memory to ";
  const std::size_t at = message.find(key);
  if (at == std::string::npos) return {};
  std::size_t used = 0;
  const double value = std::stod(message.substr(at + key.size()), &used);
  const bool gib = message.compare(at + key.size() + used, 4, " GiB") == 0;
  return std::to_string(std::uint64_t(std::ceil(value * (gib ? 1024 : 1)))) + "M";
}

// Preprocessed under --memory 16M, `input` is read in chunks, all of it, within the promise.
void expect_read_in_chunks_within_16m(const fs::path& input) {
  const ChildRun run = run_preprocess(input, fs::path(input).replace_extension(".tpi"), "16M");
  expect_within_promise(run, std::uint64_t(16) << 20);
  EXPECT_EQ(run.report.value("files_read_in_chunks", 0), 1) << run.report.dump(2);
  EXPECT_EQ(run.report.at("triangles_read").get<std::uint64_t>(), read_mesh(input).triangle_count());
}

// A 2M-triangle PLY needs about 130 MiB to read whole at 16M; it is read in chunks (with
// its part table first) within the promise. On 8e20d4c it was refused.
TEST(PreprocessMemory, AFileTooLargeToReadWholeIsReadInChunksWithinTheBudget) {
  const fs::path folder = test_folder("chunks");
  expect_read_in_chunks_within_16m(make_terrain(folder / "terrain.ply", 2'000'000));
}

// A 2M-triangle GLB, which Assimp read whole (more than 16M + 64 MiB: it was refused), is read
// by our glTF reader in chunks within the promise.
TEST(PreprocessMemory, AGlbTooLargeToReadWholeIsReadInChunksWithinTheBudget) {
  expect_read_in_chunks_within_16m(make_terrain(test_folder("glb_chunks") / "terrain.glb", 2'000'000));
}

// A terrain of about 10,000 triangles as one glTF mesh (a data URI) placed by `nodes` nodes, a
// unit apart: a file of 250 KB that places 10,000 x `nodes` triangles.
fs::path make_placed_gltf(const fs::path& path, std::size_t nodes) {
  make_terrain(path, 10'000);
  nlohmann::json document = nlohmann::json::parse(std::ifstream(path));
  nlohmann::json placed = nlohmann::json::array(), roots = nlohmann::json::array();
  for (std::size_t n = 0; n < nodes; ++n) {
    placed.push_back({{"mesh", 0}, {"translation", {double(n % 20), double(n / 20), 0.0}}});
    roots.push_back(n);
  }
  document["nodes"] = placed;
  document["scenes"] = nlohmann::json::array({{{"nodes", roots}}});
  document["scene"] = 0;
  std::ofstream(path) << document;
  return path;
}

// 300 placements of a 10k-triangle mesh in a 258 KB glTF: 3M triangles, which reading whole
// holds at about 226 MiB. Counted from the JSON (by its size, 24 B a triangle, it was 10,700
// triangles, read whole through Assimp), it is read in chunks within the promise of
// --memory 16M.
TEST(PreprocessMemory, AGltfPlacingOneMeshManyTimesIsReadInChunksWithinTheBudget) {
  const fs::path folder = test_folder("gltf_placed");
  const fs::path input = make_placed_gltf(folder / "tiles.gltf", 300);
  ASSERT_LT(fs::file_size(input), std::uintmax_t(1) << 20);
  EXPECT_GT(read_mesh(input).triangle_count(), 2'900'000u);
  expect_read_in_chunks_within_16m(input);
}

// Assimp's RAW text: a triangle a line, its nine coordinates.
fs::path write_raw(const fs::path& path, const TriangleSoup& soup) {
  std::ofstream out(path);
  out.precision(9);
  for (std::size_t t = 0; t < soup.triangle_count(); ++t) {
    for (const Vec3& p : soup.corners(t)) out << p[0] << ' ' << p[1] << ' ' << p[2] << ' ';
    out << '\n';
  }
  return path;
}

// A 500k-triangle RAW file (read whole, through Assimp) needs more than 16M + 64 MiB: refused
// before it is read, with the figure, leaving no output and no spill; at the --memory the
// message names, it runs within the promise (the estimate is an upper bound of what reading it
// takes).
TEST(PreprocessMemory, AFileTooLargeForTheBudgetIsRefusedBeforeItIsRead) {
  const fs::path folder = test_folder("refused");
  const fs::path input = write_raw(folder / "terrain.raw", read_mesh(make_terrain(folder / "terrain.ply", 500'000)));
  fs::remove(folder / "terrain.ply");
  PreprocessOptions options;
  options.memory_bytes = std::uint64_t(16) << 20;
  const std::string message = refusal({input}, folder / "terrain.tpi", options);
  EXPECT_NE(message.find("'" + input.string() + "' holds about 1,"), std::string::npos) << message;
  EXPECT_NE(message.find("above --memory 16.0 MiB + 64.0 MiB"), std::string::npos) << message;
  for (const auto& entry : fs::directory_iterator(folder))
    EXPECT_EQ(entry.path().filename(), "terrain.raw") << "left behind: " << entry.path();
  const std::string raised = raised_memory(message);
  ASSERT_FALSE(raised.empty()) << message;
  const ChildRun run = run_preprocess(input, folder / "terrain.tpi", raised.c_str());
  expect_within_promise(run, std::stoull(raised) << 20);
}

// A STEP assembly written by OCCT's XCAF writer: one sphere of radius 10 mm placed `copies`
// times, 30 mm apart in a square grid.
fs::path write_spheres(const fs::path& path, std::size_t copies) {
  Handle(TDocStd_Document) document;
  XCAFApp_Application::GetApplication()->NewDocument("MDTV-XCAF", document);
  const Handle(XCAFDoc_ShapeTool) tool = XCAFDoc_DocumentTool::ShapeTool(document->Main());
  const TDF_Label sphere = tool->AddShape(BRepPrimAPI_MakeSphere(10).Shape(), Standard_False);
  TDataStd_Name::Set(sphere, "BALL");
  const TDF_Label tray = tool->NewShape();
  TDataStd_Name::Set(tray, "tray");
  const auto side = std::size_t(std::ceil(std::sqrt(double(copies))));
  for (std::size_t k = 0; k < copies; ++k) {
    gp_Trsf placement;
    placement.SetTranslation(gp_Vec(30.0 * double(k % side), 30.0 * double(k / side), 0));
    tool->AddComponent(tray, sphere, TopLoc_Location(placement));
  }
  tool->UpdateAssemblies();
  STEPCAFControl_Writer writer;
  EXPECT_TRUE(writer.Transfer(document, STEPControl_AsIs));
  EXPECT_EQ(writer.Write(path.string().c_str()), IFSelect_RetDone);
  XCAFApp_Application::GetApplication()->Close(document);
  return path;
}

// A STEP assembly whose instances, placed, need more than 16M + 64 MiB (a sphere tessellated
// once, placed for about 2M triangles) is read in chunks within the promise: its instances
// placed a chunk at a time from the one tessellation, never held placed. Placed whole it
// needs its 2M-triangle soup and components' tables (163 MiB in the ingest under --memory 4G,
// docs/BENCHMARKS.md), more than the promise: ddbb396, which could only place it whole,
// refused it up front.
TEST(PreprocessMemory, AStepAssemblyTooLargeToHoldPlacedIsReadInChunksWithinTheBudget) {
  const fs::path folder = test_folder("step-chunks");
  const std::uint64_t per_sphere = read_mesh(write_spheres(folder / "one.step", 1)).triangle_count();
  ASSERT_GT(per_sphere, 100u);
  const std::size_t copies = std::size_t((2'000'000 + per_sphere - 1) / per_sphere);
  ASSERT_LE(copies, 10000u) << "more occurrences than a STEP file may hold by default";
  const fs::path input = write_spheres(folder / "spheres.step", copies);
  const ChildRun run = run_preprocess(input, folder / "spheres.tpi", "16M");
  expect_within_promise(run, std::uint64_t(16) << 20, true);
  EXPECT_EQ(run.report.value("files_read_in_chunks", 0), 1) << run.report.dump(2);
  EXPECT_EQ(run.report.at("parts").get<std::uint64_t>(), copies);
  const TriangleSoup whole = read_mesh(input);
  EXPECT_EQ(run.report.at("triangles_read").get<std::uint64_t>(), whole.triangle_count());
  // Each sphere a closed component of its own, found across the chunks' seams.
  EXPECT_EQ(run.report.at("components").get<std::uint64_t>(), copies);
  EXPECT_EQ(run.report.at("closed_components").get<std::uint64_t>(), copies);
}

// Writes `soup` as ASCII PLY, binary PLY of float vertices, or ASCII STL (formats MeshWriter
// does not write).
void write_as(const TriangleSoup& soup, const fs::path& path, const std::string& kind) {
  std::ofstream out(path, std::ios::binary);
  if (kind == "stl-ascii") {
    out << "solid t\n";
    for (std::size_t t = 0; t < soup.triangle_count(); ++t) {
      out << "facet normal 0 0 1\nouter loop\n";
      for (const Vec3& p : soup.corners(t)) out << "vertex " << p[0] << ' ' << p[1] << ' ' << p[2] << '\n';
      out << "endloop\nendfacet\n";
    }
    out << "endsolid t\n";
    return;
  }
  const bool ascii = kind == "ply-ascii";
  out << "ply\nformat " << (ascii ? "ascii" : "binary_little_endian") << " 1.0\nelement vertex "
      << soup.vertices.size() << "\nproperty float x\nproperty float y\nproperty float z\n"
      << "element face " << soup.triangle_count() << "\nproperty list uchar int vertex_indices\n"
      << "end_header\n";
  for (const Vec3& p : soup.vertices) {
    const float xyz[3] = {float(p[0]), float(p[1]), float(p[2])};
    if (ascii) out << xyz[0] << ' ' << xyz[1] << ' ' << xyz[2] << '\n';
    else out.write(reinterpret_cast<const char*>(xyz), sizeof xyz);
  }
  for (const TriangleIndices& t : soup.triangles) {
    if (ascii) {
      out << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
      continue;
    }
    const unsigned char three = 3;
    out.write(reinterpret_cast<const char*>(&three), 1);
    out.write(reinterpret_cast<const char*>(t.data()), 12);
  }
}

class ReadEstimate : public testing::TestWithParam<std::string> {};

// Each reader's estimate, from the header or the size, is at least what its soup takes.
TEST_P(ReadEstimate, IsAnUpperBoundOfTheSoup) {
  const fs::path folder = test_folder("estimate-" + GetParam());
  const TriangleSoup terrain = read_mesh(make_terrain(folder / "terrain.ply", 20'000));
  const std::string kind = GetParam();
  fs::path path = folder / ("t." + kind.substr(0, kind.find('-')));
  if (kind == "ply-double") path = folder / "terrain.ply";
  else if (kind.find('-') != std::string::npos) write_as(terrain, path, kind);
  else make_terrain(path, 20'000);
  const TriangleSoup soup = read_mesh(path);
  const std::uint64_t held = soup.vertices.capacity() * sizeof(Vec3) +
                             soup.triangles.capacity() * sizeof(TriangleIndices) +
                             soup.part_of.capacity() * sizeof(std::uint32_t);
  const MeshReadEstimate estimate = estimate_mesh_read(path);
  EXPECT_GE(estimate.triangles, soup.triangle_count()) << path;
  EXPECT_GE(estimate.soup_bytes(), held) << path;
  EXPECT_GE(estimate.reading_bytes, held) << path;
  EXPECT_LE(estimate.soup_bytes(), 3 * held) << path;
}

INSTANTIATE_TEST_SUITE_P(Formats, ReadEstimate,
                         testing::Values("ply-ascii", "ply-float", "ply-double", "stl",
                                         "stl-ascii", "obj", "off"),
                         [](const testing::TestParamInfo<std::string>& param) {
                           std::string name = param.param;
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });

// A full disk cannot be made here: the free space is injected (assumed_free_disk_bytes). 2,000
// copies of 968 triangles need about 200 MiB of spill and index under 16M; with 64 MiB free
// the run is refused once the part's file is read, before any copy is placed.
TEST(PreprocessMemory, AModelTheDiskCannotHoldIsRefusedWithTheFigure) {
  const fs::path folder = test_folder("disk");
  const fs::path manifest = make_manifest(folder, make_terrain(folder / "part.ply", 1000), 20, 100);
  PreprocessOptions options;
  options.memory_bytes = std::uint64_t(16) << 20;
  options.assumed_free_disk_bytes = std::uint64_t(64) << 20;
  const std::string message = refusal({manifest}, folder / "model.tpi", options);
  EXPECT_NE(message.find("the model places 1.9e+06 triangles, about "), std::string::npos)
      << message;
  EXPECT_NE(message.find("has 64.0 MiB free"), std::string::npos) << message;
  for (const auto& entry : fs::directory_iterator(folder))
    EXPECT_EQ(entry.path().filename().string().find("spill"), std::string::npos) << entry.path();
  EXPECT_FALSE(fs::exists(folder / "model.tpi"));
  // With the room it needs, the same model is written.
  options.assumed_free_disk_bytes = std::uint64_t(1) << 30;
  options.memory_bytes = std::uint64_t(64) << 20;
  EXPECT_NO_THROW(preprocess({manifest}, folder / "model.tpi", options));
}

// A file whose triangles follow no spatial order (a terrain's, shuffled) makes about one piece of
// a component per triangle in each chunk: read in chunks under 16M, its labels pass a quarter of
// the budget and the run is refused with the figure, leaving nothing behind.
TEST(PreprocessMemory, AFileInNoSpatialOrderIsRefusedWithTheFigureWhenItsPiecesExceedTheBudget) {
  const fs::path folder = test_folder("shuffled");
  TriangleSoup terrain = read_mesh(make_terrain(folder / "terrain.ply", 1'500'000));
  std::mt19937_64 random(7);
  std::shuffle(terrain.triangles.begin(), terrain.triangles.end(), random);
  const fs::path input = folder / "shuffled.ply";
  write_as(terrain, input, "ply-float");
  fs::remove(folder / "terrain.ply");
  PreprocessOptions options;
  options.memory_bytes = std::uint64_t(16) << 20;
  options.force_spill = true;  // read in chunks
  const std::string message = refusal({input}, folder / "model.tpi", options);
  EXPECT_NE(message.find("pieces of connected components"), std::string::npos) << message;
  EXPECT_NE(message.find("above a quarter of --memory 16.0 MiB"), std::string::npos) << message;
  // The figure: a quarter of it holds the labels of the whole file at the rate so far.
  const std::string raised = raised_memory(message);
  ASSERT_FALSE(raised.empty()) << message;
  EXPECT_GE(std::stoull(raised), 32u) << message;
  for (const auto& entry : fs::directory_iterator(folder))
    EXPECT_EQ(entry.path().filename(), "shuffled.ply") << "left behind: " << entry.path();
}

// A file read in chunks is weighed against the free disk before it is read: 300,000 triangles
// need about 30 MiB of spill and index; with 8 MiB free the run is refused with the figure.
TEST(PreprocessMemory, AFileReadInChunksTheDiskCannotHoldIsRefusedBeforeItIsRead) {
  const fs::path folder = test_folder("disk-chunks");
  const fs::path input = make_terrain(folder / "terrain.ply", 300'000);
  PreprocessOptions options;
  options.force_spill = true;  // read in chunks
  options.assumed_free_disk_bytes = std::uint64_t(8) << 20;
  // Before it is read: no triangle of it is counted (read, its progress ends with its count).
  std::uint64_t chunked_triangles = 0;
  options.on_progress = [&](std::string_view label, std::uint64_t done, std::uint64_t) {
    if (label.find("in chunks") != std::string_view::npos) chunked_triangles = done;
  };
  const std::string message = refusal({input}, folder / "model.tpi", options);
  EXPECT_NE(message.find("the model places 3e+05 triangles, about "), std::string::npos) << message;
  EXPECT_NE(message.find("has 8.0 MiB free"), std::string::npos) << message;
  EXPECT_EQ(chunked_triangles, 0u);
  // The counter does see a read: with room on the disk, the file's triangles are counted.
  options.assumed_free_disk_bytes = std::uint64_t(1) << 30;
  preprocess({input}, folder / "model.tpi", options);
  EXPECT_GT(chunked_triangles, 290'000u) << "the progress does not count the chunks read";
  fs::remove(folder / "model.tpi");
  for (const auto& entry : fs::directory_iterator(folder))
    EXPECT_EQ(entry.path().filename(), "terrain.ply") << "left behind: " << entry.path();
}

// Copies placed in batches (16M: about 10 copies a batch) store the triangles of the soup placed
// whole (load_inputs), with the same ids and parts: every tet checked against brute force.
TEST(PreprocessMemory, BatchedCopiesStoreTheSameTrianglesIdsAndParts) {
  const fs::path folder = test_folder("batches");
  const fs::path manifest = make_manifest(folder, make_tetras_part(folder, 400), 2, 100);
  PreprocessOptions options;
  options.memory_bytes = std::uint64_t(16) << 20;
  options.force_spill = true;
  const fs::path output = folder / "model.tpi";
  const PreprocessSummary summary = preprocess({manifest}, output, options);
  const TriangleSoup whole = load_inputs({manifest});
  EXPECT_EQ(summary.triangles_read, whole.triangle_count());
  EXPECT_EQ(summary.parts, whole.part_count());
  const IndexReader index(output);
  const TetMesh mesh = index.read_mesh();
  std::vector<std::uint32_t> tets(mesh.tet_count());
  for (std::uint32_t t = 0; t < tets.size(); ++t) tets[t] = t;
  AuditFindings findings;
  audit_binning(index, input_pieces({manifest}), tets, findings);
  EXPECT_EQ(findings.mismatches, 0u);
  const auto component_part = index.read_table_uint32("component_part");
  for (std::uint32_t s = 0; s < index.shard_count(); ++s) {
    const Shard shard = Shard::decode(index.read_shard(s));
    for (std::uint32_t local = 0; local < shard.triangle_count(); ++local) {
      const std::uint64_t id = shard.triangle_id(local);
      ASSERT_LT(id, whole.triangle_count());
      EXPECT_EQ(component_part.at(shard.component_id(local)), whole.part_of[id]);
    }
  }
}

}  // namespace
}  // namespace tetrapage
