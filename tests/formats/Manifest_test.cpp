// Assembly manifests: parsing, instancing (each file read once), transforms against Eigen,
// units, and errors that name the manifest and the JSON path of the bad field.

#include <Eigen/Geometry>

#include "TestSupport.h"
#include "tetrapage/formats/Manifest.h"
#include "tetrapage/formats/MeshWriter.h"

namespace tetrapage::test {
namespace {

/// A tetrahedron surface (4 triangles) as OFF text.
constexpr const char* tetrahedron_off =
    "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";

Eigen::Matrix4d to_eigen(const Transform& t) {
  return Eigen::Map<const Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(t.data());
}

struct AssemblyFiles {
  std::filesystem::path folder, manifest;
};

AssemblyFiles write_assembly(const std::string& name, const std::string& json) {
  AssemblyFiles files;
  files.folder = scratch_folder(name);
  std::filesystem::create_directories(files.folder / "sub");
  write_file(files.folder / "sub" / "bracket.off", tetrahedron_off);
  write_file(files.folder / "frame.obj", "v 0 0 0\nv 2 0 0\nv 0 2 0\nf 1 2 3\n");
  files.manifest = files.folder / "assembly.json";
  write_file(files.manifest, json);
  return files;
}

const char* example_manifest = R"({
  // comments are allowed
  "units": "mm",
  "parts": [
    { "name": "bracket", "file": "sub/bracket.off", "units": "in",
      "instances": [ { "translation": [1, 2, 3] },
                     { "rotation": [0, 0, 0, 2], "scale": 2 },
                     { "matrix": [0, -1, 0, 5,  1, 0, 0, 6,  0, 0, 1, 7,  0, 0, 0, 1] },
                     { "translation": [0.5, 0, -1], "rotation": [0.9, 0.1, -0.3, 0.2],
                       "scale": [1, 2, 3] } ] },
    { "file": "frame.obj" }
  ]
})";

TEST(Manifest, ReadsPartsUnitsAndInstances) {
  const auto files = write_assembly("manifest_read", example_manifest);
  const Manifest manifest = read_manifest(files.manifest);
  EXPECT_EQ(manifest.path, files.manifest);
  EXPECT_EQ(manifest.units, "mm");
  ASSERT_EQ(manifest.parts.size(), 2u);
  const ManifestPart& bracket = manifest.parts[0];
  EXPECT_EQ(bracket.name, "bracket");
  EXPECT_EQ(bracket.file, files.folder / "sub/bracket.off");
  EXPECT_DOUBLE_EQ(bracket.unit_scale, 25.4);
  ASSERT_EQ(bracket.instances.size(), 4u);
  EXPECT_EQ(bracket.instances[0], (Transform{1, 0, 0, 1, 0, 1, 0, 2, 0, 0, 1, 3, 0, 0, 0, 1}));
  // Half a turn about z (the quaternion is normalised), then scale 2.
  EXPECT_EQ(bracket.instances[1], (Transform{-2, 0, 0, 0, 0, -2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 1}));
  EXPECT_EQ(bracket.instances[2], (Transform{0, -1, 0, 5, 1, 0, 0, 6, 0, 0, 1, 7, 0, 0, 0, 1}));
  // T * R * S against Eigen.
  const Eigen::Affine3d expected = Eigen::Translation3d(0.5, 0, -1) *
                                   Eigen::Quaterniond(0.9, 0.1, -0.3, 0.2).normalized() *
                                   Eigen::Scaling(1.0, 2.0, 3.0);
  EXPECT_TRUE(to_eigen(bracket.instances[3]).isApprox(expected.matrix(), 1e-15))
      << to_eigen(bracket.instances[3]) << "\nvs\n"
      << expected.matrix();
  const ManifestPart& frame = manifest.parts[1];
  EXPECT_EQ(frame.name, "frame");
  EXPECT_EQ(frame.unit_scale, 1.0);
  EXPECT_EQ(frame.instances, std::vector<Transform>{identity_transform()});
}

TEST(Manifest, LoadAssemblyReadsEachFileOnceAndPlacesEveryInstance) {
  const auto files = write_assembly("manifest_load", example_manifest);
  const Manifest manifest = read_manifest(files.manifest);
  std::vector<ReadReport> reports;
  const TriangleSoup assembly = load_assembly(manifest, &reports);
  ASSERT_EQ(reports.size(), 2u);  // one per file, not per instance
  EXPECT_EQ(reports[0].path, (files.folder / "sub/bracket.off").string());
  EXPECT_EQ(assembly.part_names, (std::vector<std::string>{"bracket#0", "bracket#1", "bracket#2",
                                                           "bracket#3", "frame"}));
  ASSERT_EQ(assembly.triangle_count(), 4u * 4u + 1u);
  const TriangleSoup bracket = read_mesh(files.folder / "sub" / "bracket.off");
  for (std::size_t t = 0; t < assembly.triangle_count(); ++t) {
    const std::uint32_t part = assembly.part_of[t];
    if (part == 4) {
      EXPECT_EQ(assembly.corners(t),
                (std::array<Vec3, 3>{Vec3{0, 0, 0}, Vec3{2, 0, 0}, Vec3{0, 2, 0}}));
      continue;
    }
    // Instance `part` of the bracket: inches to millimetres, then the instance transform.
    const Eigen::Matrix4d m = to_eigen(manifest.parts[0].instances[part]);
    const auto source = bracket.corners(t - 4 * part);
    const auto placed = assembly.corners(t);
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector4d expected =
          m * Eigen::Vector4d(25.4 * source[k][0], 25.4 * source[k][1], 25.4 * source[k][2], 1);
      for (int a = 0; a < 3; ++a)
        EXPECT_NEAR(placed[k][a], expected[a], 1e-12) << "triangle " << t << " corner " << k;
    }
  }
}

TEST(Manifest, IdentityAndIntegerTranslationsAreExact) {
  const auto files = write_assembly("manifest_exact", R"({"parts": [
      {"name": "b", "file": "sub/bracket.off", "instances": [{}, {"translation": [10, -20, 30]}]}]})");
  const TriangleSoup assembly = load_assembly(read_manifest(files.manifest));
  const TriangleSoup bracket = read_mesh(files.folder / "sub" / "bracket.off");
  ASSERT_EQ(assembly.vertices.size(), 2 * bracket.vertices.size());
  for (std::size_t v = 0; v < bracket.vertices.size(); ++v) {
    const Vec3& p = bracket.vertices[v];
    EXPECT_EQ(assembly.vertices[v], p);
    EXPECT_EQ(assembly.vertices[v + 4], (Vec3{p[0] + 10, p[1] - 20, p[2] + 30}));
  }
  EXPECT_EQ(assembly.part_names, (std::vector<std::string>{"b#0", "b#1"}));
}

TEST(Manifest, MultiPartFilesKeepTheirNodeNames) {
  const auto folder = scratch_folder("manifest_gltf");
  TriangleSoup robot = random_soup(5, 2, 20);
  write_mesh(folder / "robot.glb", robot);
  write_file(
      folder / "cell.json",
      R"({"parts": [{"name": "arm", "file": "robot.glb", "instances": [{}, {"scale": 2}]}]})");
  const TriangleSoup assembly = load_assembly(read_manifest(folder / "cell.json"));
  EXPECT_EQ(assembly.part_names,
            (std::vector<std::string>{"arm#0/part0", "arm#0/part1", "arm#1/part0", "arm#1/part1"}));
  EXPECT_EQ(assembly.triangle_count(), 2 * robot.triangle_count());
}

TEST(Manifest, LoadInputsMixesMeshesAndManifests) {
  const auto files = write_assembly("manifest_inputs", example_manifest);
  std::vector<ReadReport> reports;
  const TriangleSoup all = load_inputs({files.folder / "frame.obj", files.manifest}, &reports);
  ASSERT_EQ(reports.size(), 3u);
  EXPECT_EQ(all.part_count(), 6u);
  EXPECT_EQ(all.part_names[0], "frame");
  EXPECT_EQ(all.part_names[1], "bracket#0");
  EXPECT_EQ(all.triangle_count(), 1u + 16u + 1u);
  // Indices were shifted: every triangle of the last part uses the last three vertices.
  const auto last = all.triangles.back();
  EXPECT_EQ(last, (TriangleIndices{static_cast<std::uint32_t>(all.vertices.size() - 3),
                                   static_cast<std::uint32_t>(all.vertices.size() - 2),
                                   static_cast<std::uint32_t>(all.vertices.size() - 1)}));
}

TEST(Manifest, MetresPerUnit) {
  EXPECT_EQ(metres_per_unit("m"), 1.0);
  EXPECT_EQ(metres_per_unit("cm"), 0.01);
  EXPECT_EQ(metres_per_unit("mm"), 0.001);
  EXPECT_EQ(metres_per_unit("um"), 1e-6);
  EXPECT_EQ(metres_per_unit("in"), 0.0254);
  EXPECT_EQ(metres_per_unit("ft"), 0.3048);
  expect_error<InputError>([] { metres_per_unit("furlong"); }, {"furlong"});
}

struct BadManifest {
  const char* json;
  bool input_error;  ///< else FormatError
  std::vector<std::string> message_parts;
};

TEST(Manifest, ErrorsNameTheFileAndTheJsonPath) {
  const std::vector<BadManifest> cases = {
      {R"({"parts": [ {"file": "frame.obj"}, )", false, {"JSON"}},
      {R"([1, 2])", false, {"top level", "object"}},
      {R"({"units": "m"})", false, {"'parts'"}},
      {R"({"parts": {"file": "frame.obj"}})", false, {"parts:", "array"}},
      {R"({"parts": []})", true, {"parts:", "no part"}},
      {R"({"units": "furlong", "parts": [{"file": "frame.obj"}]})", true, {"units:", "furlong"}},
      {R"({"parts": [{"file": "frame.obj", "units": 3}]})", false, {"parts[0].units", "string"}},
      {R"({"parts": [{"file": "frame.obj", "units": "yd"}]})", true, {"parts[0].units", "'yd'"}},
      {R"({"parts": [{"name": "x"}]})", false, {"parts[0]", "'file'"}},
      {R"({"parts": [{"file": "frame.obj", "instance": []}]})", false, {"parts[0]", "'instance'"}},
      {R"({"parts": [{"file": "frame.obj"}, {"file": "sub/frame.obj"}]})",
       true,
       {"parts[1].name", "duplicate", "'frame'"}},
      {R"({"parts": [{"file": "frame.obj", "instances": []}]})", false, {"parts[0].instances"}},
      {R"({"parts": [{"file": "frame.obj"}, {"file": "sub/bracket.off", "instances": [
          {"matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0]}]}]})",
       false,
       {"parts[1].instances[0].matrix", "16 numbers"}},
      {R"({"parts": [{"file": "frame.obj", "instances": [
          {"matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,1,1]}]}]})",
       true,
       {"parts[0].instances[0].matrix", "0 0 0 1"}},
      {R"({"parts": [{"file": "frame.obj", "instances": [
          {"matrix": [1,0,0,0, 2,0,0,0, 0,0,1,0, 0,0,0,1]}]}]})",
       true,
       {"parts[0].instances[0]", "singular"}},
      {R"({"parts": [{"file": "frame.obj", "instances": [{}, {"scale": [1, 0, 1]}]}]})",
       true,
       {"parts[0].instances[1]", "singular"}},
      {R"({"parts": [{"file": "frame.obj", "instances": [{"rotation": [0, 0, 0, 0]}]}]})",
       true,
       {"parts[0].instances[0].rotation", "normalised"}},
      {R"({"parts": [{"file": "frame.obj", "instances": [{"translation": [1, "a", 3]}]}]})",
       false,
       {"parts[0].instances[0].translation[1]", "\"a\""}},
      {R"({"parts": [{"file": "frame.obj", "instances": [{"translation": [1, 2]}]}]})",
       false,
       {"parts[0].instances[0].translation", "3 numbers"}},
      {R"({"parts": [{"file": "frame.obj", "instances": [{"matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0,
          0,0,0,1], "scale": 2}]}]})",
       false,
       {"parts[0].instances[0]", "not both"}},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const auto files = write_assembly("manifest_bad", cases[i].json);
    std::vector<std::string> parts = cases[i].message_parts;
    parts.push_back(files.manifest.string());
    SCOPED_TRACE("case " + std::to_string(i) + ": " + cases[i].json);
    if (cases[i].input_error) {
      expect_error<InputError>([&] { read_manifest(files.manifest); }, parts);
    } else {
      expect_error<FormatError>([&] { read_manifest(files.manifest); }, parts);
    }
  }
}

TEST(Manifest, MissingFilesAreIoErrors) {
  const auto folder = scratch_folder("manifest_missing");
  expect_error<IoError>([&] { read_manifest(folder / "none.json"); }, {"none.json"});
  write_file(folder / "a.json", R"({"parts": [{"file": "gone.stl"}]})");
  const Manifest manifest = read_manifest(folder / "a.json");  // files are opened by the load
  expect_error<IoError>([&] { load_assembly(manifest); }, {(folder / "gone.stl").string()});
}

}  // namespace
}  // namespace tetrapage::test
