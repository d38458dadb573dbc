// tetrapage render: the PNG encoding round-trips (and a corrupted file is refused), and the
// picture of a box seen face-on covers exactly the square that perspective projection predicts
// (an analytic oracle), with the flight path drawn over it; bad requests are clear errors, and
// the file written is in the format its extension names (or none is written).

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "BoxSoup.h"
#include "RunCli.h"
#include "TestFiles.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/preprocess/Preprocess.h"
#include "tetrapage/tools/ModelRenderer.h"
#include "tetrapage/tools/Random.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;

struct Folder {
  fs::path path = fs::path(TETRAPAGE_TEST_TMP) / ("render-" + std::to_string(::getpid()));
  Folder() { fs::create_directories(path); }
  ~Folder() {
    std::error_code ignored;
    fs::remove_all(path, ignored);
  }
};

TEST(PngImage, RoundTripsAndRefusesCorruption) {
  Folder folder;
  Random random(3);
  RgbImage image(37, 23);
  for (auto& p : image.pixels) p = std::uint8_t(random.uniform(0, 256));
  const fs::path path = folder.path / "image.png";
  write_png(path, image);
  const RgbImage back = read_png(path);
  EXPECT_EQ(back.width, 37u);
  EXPECT_EQ(back.height, 23u);
  EXPECT_EQ(back.pixels, image.pixels);
  // Flip one byte of the image data: the chunk's CRC no longer matches.
  {
    std::fstream file(path, std::ios::in | std::ios::out | std::ios::binary);
    file.seekp(60);
    char c = 0;
    file.read(&c, 1);
    file.seekp(60);
    c = char(c ^ 0x55);
    file.write(&c, 1);
  }
  EXPECT_THROW(read_png(path), FormatError);
  EXPECT_THROW(write_png(folder.path / "empty.png", RgbImage(0, 0)), InputError);
  EXPECT_THROW(write_png(folder.path / "no-such-folder" / "x.png", image), IoError);
  EXPECT_FALSE(fs::exists(folder.path / "no-such-folder"));
}

// A cube [0.4, 0.6]^3 indexed, viewed along -x (azimuth 0, elevation 0).
TEST(Render, ACubeFaceOnCoversThePredictedSquare) {
  Folder folder;
  TriangleSoup soup;
  test::add_box(soup, {0.4, 0.4, 0.4}, {0.6, 0.6, 0.6});
  const fs::path input = folder.path / "cube.ply", index_path = folder.path / "cube.tpi";
  write_mesh(input, soup);
  PreprocessOptions p;
  p.region_triangles = 4;
  p.precision = StoredPrecision::float64;
  preprocess({input}, index_path, p);
  const CollisionIndex index(index_path);

  RenderOptions options;
  options.width = 400;
  options.height = 400;
  options.azimuth_degrees = 0;
  options.elevation_degrees = 0;
  // A path across the front of the cube, at x = 0.7 (between the camera and the face).
  options.path = {{0.7, 0.3, 0.5}, {0.7, 0.7, 0.5}};
  RenderSummary summary;
  const RgbImage image = render_model(index, options, summary);
  EXPECT_EQ(summary.triangles_drawn, 12u);
  EXPECT_EQ(summary.stride, 1u);
  // The oracle: the camera sits on the x axis through the centre at r / sin(20 deg) (r the
  // half diagonal 0.1 sqrt 3) and sees the face x = 0.6 at distance D - 0.1; its half side
  // 0.1 spans 0.1 / ((D - 0.1) tan 20 deg) of the half image.
  const double deg = std::numbers::pi / 180;
  const double distance = 0.1 * std::sqrt(3.0) / std::sin(20 * deg);
  const double half_side_px = 0.1 / ((distance - 0.1) * std::tan(20 * deg)) * 200;
  const double predicted = (2 * half_side_px) * (2 * half_side_px);
  EXPECT_NEAR(double(summary.pixels_hit), predicted, 0.03 * predicted)
      << "hit " << summary.pixels_hit << " pixels, the projection predicts " << predicted;
  // The centre pixel is on the cube and lit; a corner pixel is sky.
  auto is_magenta = [&](std::size_t x, std::size_t y) {
    const auto* px = image.at(x, y);
    return px[0] > 180 && px[1] < 80 && px[2] > 120;
  };
  const auto* centre = image.at(200, 150);
  EXPECT_FALSE(centre[0] == centre[1] && centre[1] == centre[2]) << "the cube is coloured, not grey";
  std::size_t magenta = 0;
  for (std::size_t x = 0; x < 400; ++x) magenta += is_magenta(x, 200);
  EXPECT_GT(magenta, 100u) << "the path crosses the image's middle row";
}

TEST(Render, BadRequestsAreClearErrors) {
  Folder folder;
  TriangleSoup soup;
  test::add_box(soup, {0, 0, 0}, {1, 1, 1});
  const fs::path input = folder.path / "box.ply", index_path = folder.path / "box.tpi";
  write_mesh(input, soup);
  preprocess({input}, index_path, PreprocessOptions{});
  const CollisionIndex index(index_path);
  RenderSummary summary;
  RenderOptions zero;
  zero.width = 0;
  EXPECT_THROW(render_model(index, zero, summary), InputError);
  RenderOptions counts;
  counts.colouring = RenderColouring::page_ins;
  counts.page_ins.assign(index.shard_count() + 1, 1);
  EXPECT_THROW(render_model(index, counts, summary), InputError);
  counts.page_ins.pop_back();
  EXPECT_NO_THROW(render_model(index, counts, summary));
  // The CLI: page-ins need a flight and an object.
  const std::string command = std::string(TETRAPAGE_CLI) + " render " + index_path.string() + " -o " +
                              (folder.path / "x.png").string() + " --color page-ins 2>/dev/null";
  EXPECT_NE(std::system(command.c_str()), 0);
  EXPECT_FALSE(fs::exists(folder.path / "x.png"));
}

// The picture's format follows its extension: a .png file (any case) starts with PNG's
// signature and decodes; any other extension, or none, is refused before the work with one line
// naming the path and what render writes, and leaves no file (nor the report).
TEST(Render, WritesTheFormatItsExtensionNamesOrRefuses) {
  Folder folder;
  TriangleSoup soup;
  test::add_box(soup, {0, 0, 0}, {1, 1, 1});
  write_mesh(folder.path / "box.ply", soup);
  preprocess({folder.path / "box.ply"}, folder.path / "box.tpi", PreprocessOptions{});
  const std::string render = "render box.tpi --size 40x30 --report r.json -o ";
  const unsigned char png_signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  for (const char* name : {"view.png", "VIEW.PNG"}) {
    const test::CliResult run = test::run_cli_in(folder.path, render + name);
    ASSERT_EQ(run.status, 0) << name << ": " << run.err;
    const std::string bytes = test::file_bytes(folder.path / name);
    ASSERT_GE(bytes.size(), 8u) << name;
    EXPECT_EQ(std::memcmp(bytes.data(), png_signature, 8), 0)
        << name << " does not start with PNG's signature";
    const RgbImage image = read_png(folder.path / name);
    EXPECT_EQ(image.width, 40u);
    EXPECT_EQ(image.height, 30u);
    fs::remove(folder.path / "r.json");
  }
  for (const char* name : {"view.jpg", "view", "view.ppm", "view.png.bak", "view.svg"}) {
    const test::CliResult run = test::run_cli_in(folder.path, render + name);
    EXPECT_EQ(run.status, 1) << name;
    EXPECT_EQ(run.err.find('\n'), run.err.size() - 1) << "one line: " << run.err;
    EXPECT_NE(run.err.find(std::string("'") + name + "'"), std::string::npos)
        << "names the path: " << run.err;
    EXPECT_NE(run.err.find("PNG (.png)"), std::string::npos)
        << "names the formats written: " << run.err;
    EXPECT_FALSE(fs::exists(folder.path / name)) << name;
    EXPECT_FALSE(fs::exists(folder.path / "r.json")) << name;
    for (const auto& entry : fs::directory_iterator(folder.path))
      EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
  }
}

}  // namespace
}  // namespace tetrapage
