// Assembly manifests: parsing, instancing (each file read once), transforms against Eigen,
// units, and errors that name the manifest and the JSON path of the bad field.

#include <Eigen/Geometry>

#include "TestSupport.h"
#include "tetrapage/formats/mesh/Manifest.h"
#include "tetrapage/formats/mesh/MeshWriter.h"

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
  // Instances share the part's name; their paths tell them apart.
  EXPECT_EQ(assembly.part_names,
            (std::vector<std::string>{"bracket", "bracket", "bracket", "bracket", "frame"}));
  EXPECT_EQ(assembly.part_paths, (std::vector<std::string>{"bracket#0", "bracket#1", "bracket#2",
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
  EXPECT_EQ(assembly.part_names, (std::vector<std::string>{"b", "b"}));
  EXPECT_EQ(assembly.part_paths, (std::vector<std::string>{"b#0", "b#1"}));
}

TEST(Manifest, MultiPartFilesKeepTheirNodeNames) {
  const auto folder = scratch_folder("manifest_gltf");
  TriangleSoup robot = random_soup(5, 2, 20);
  write_mesh(folder / "robot.glb", robot);
  write_file(
      folder / "cell.json",
      R"({"parts": [{"name": "arm", "file": "robot.glb", "instances": [{}, {"scale": 2}]}]})");
  const TriangleSoup assembly = load_assembly(read_manifest(folder / "cell.json"));
  EXPECT_EQ(assembly.part_names, (std::vector<std::string>{"part0", "part1", "part0", "part1"}));
  EXPECT_EQ(assembly.part_paths,
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
  EXPECT_EQ(all.part_names[1], "bracket");
  EXPECT_EQ(all.part_path(1), "bracket#0");
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
      {R"({"parts": [{"file": "frame.obj", "manifest": "sub.json"}]})",
       false,
       {"parts[0]", "not both"}},
      {R"({"parts": [{"manifest": "sub.json", "units": "mm"}]})",
       false,
       {"parts[0].units", "sub-assembly"}},
      {R"({"parts": [{"file": "sub.json"}]})", false, {"parts[0].file", "'manifest'"}},
      {R"({"parts": [{"manifest": ""}]})", false, {"parts[0].manifest", "empty"}},
      {R"({"parts": [{"file": "frame.obj"}], "parts": [{"file": "sub/bracket.off"}]})",
       false,
       {"'parts'", "twice"}},
      {R"({"parts": [{"file": "frame.obj", "instances": [{"translation": [1, 2, 3], "translation": [0, 0, 0]}]}]})",
       false,
       {"'translation'", "twice"}},
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

// cell.json (m) holds rack.json (cm) once; the rack holds board.json (mm) twice and a frame; the
// board holds U7 twice and U8 (in inches) once. Paths go up and down folders.
struct NestedAssembly {
  std::filesystem::path folder, top;
};

NestedAssembly write_nested_assembly(const std::string& name) {
  NestedAssembly files;
  files.folder = scratch_folder(name);
  std::filesystem::create_directories(files.folder / "racks");
  std::filesystem::create_directories(files.folder / "boards");
  write_file(files.folder / "boards" / "u7.off", tetrahedron_off);
  write_file(files.folder / "boards" / "u8.off", tetrahedron_off);
  write_file(files.folder / "frame.obj", "v 0 0 0\nv 2 0 0\nv 0 2 0\nf 1 2 3\n");
  files.top = files.folder / "cell.json";
  write_file(files.top, R"({"parts": [{"name": "rack", "manifest": "racks/rack.json",
      "instances": [{"translation": [1, 2, 3], "rotation": [0.9, 0.1, -0.3, 0.2]}]}]})");
  write_file(files.folder / "racks" / "rack.json", R"({"units": "cm", "parts": [
      {"name": "board", "manifest": "../boards/board.json", "instances": [
          {"translation": [10, 0, 0]}, {"rotation": [0, 0, 0, 1], "scale": 2, "translation": [0, 5, 0]}]},
      {"name": "frame", "file": "../frame.obj"}]})");
  write_file(files.folder / "boards" / "board.json", R"({"units": "mm", "parts": [
      {"name": "U7", "file": "u7.off",
       "instances": [{}, {"matrix": [0, -1, 0, 5,  1, 0, 0, 6,  0, 0, 1, 7,  0, 0, 0, 1]}]},
      {"name": "U8", "file": "u8.off", "units": "in", "instances": [{"translation": [0.5, 0, 0]}]}]})");
  return files;
}

TEST(Manifest, NestedAssembliesComposeTransformsAndUnits) {
  const auto files = write_nested_assembly("nested");
  std::vector<ReadReport> reports;
  const TriangleSoup assembly = load_assembly(read_manifest(files.top), &reports);
  EXPECT_EQ(reports.size(), 3u);  // u7, u8, frame: each mesh entry read once
  EXPECT_EQ(assembly.part_names,
            (std::vector<std::string>{"U7", "U7", "U7", "U7", "U8", "U8", "frame"}));
  EXPECT_EQ(assembly.part_paths,
            (std::vector<std::string>{"rack/board#0/U7#0", "rack/board#0/U7#1", "rack/board#1/U7#0",
                                      "rack/board#1/U7#1", "rack/board#0/U8", "rack/board#1/U8",
                                      "rack/frame"}));

  // The placements composed by hand, units as scalings: cm -> m, mm -> cm, in -> mm.
  using Eigen::Affine3d, Eigen::Scaling, Eigen::Translation3d, Eigen::Quaterniond;
  const Affine3d rack =
      Translation3d(1, 2, 3) * Quaterniond(0.9, 0.1, -0.3, 0.2).normalized() * Scaling(0.01);
  const Affine3d boards[2] = {
      Translation3d(10, 0, 0) * Scaling(0.1),
      Translation3d(0, 5, 0) * Quaterniond(0, 0, 0, 1) * Scaling(2.0) * Scaling(0.1)};
  Affine3d u7_turned = Affine3d::Identity();
  u7_turned.matrix() << 0, -1, 0, 5, 1, 0, 0, 6, 0, 0, 1, 7, 0, 0, 0, 1;
  const Affine3d u7[2] = {Affine3d::Identity(), u7_turned};
  const Affine3d u8 = Translation3d(0.5, 0, 0) * Scaling(25.4);
  std::vector<Affine3d> expected;
  for (const auto& board : boards)
    for (const auto& instance : u7) expected.push_back(rack * board * instance);
  for (const auto& board : boards) expected.push_back(rack * board * u8);
  expected.push_back(rack);

  const TriangleSoup tetrahedron = read_mesh(files.folder / "boards" / "u7.off");
  const TriangleSoup frame = read_mesh(files.folder / "frame.obj");
  ASSERT_EQ(assembly.triangle_count(), 6 * tetrahedron.triangle_count() + frame.triangle_count());
  for (std::size_t t = 0; t < assembly.triangle_count(); ++t) {
    const std::uint32_t part = assembly.part_of[t];
    const auto source = part < 6 ? tetrahedron.corners(t - 4 * part) : frame.corners(0);
    const auto placed = assembly.corners(t);
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d want =
          expected[part] * Eigen::Vector3d(source[k][0], source[k][1], source[k][2]);
      for (int a = 0; a < 3; ++a)
        EXPECT_NEAR(placed[k][a], want[a], 1e-14) << "triangle " << t << " corner " << k;
    }
  }
}

TEST(Manifest, InputPiecesOfANestedAssemblyGiveTheSoupOfLoadInputs) {
  const auto files = write_nested_assembly("nested_pieces");
  const std::vector<std::filesystem::path> inputs = {files.folder / "frame.obj", files.top};
  const TriangleSoup all = load_inputs(inputs);
  const std::vector<InputPiece> pieces = input_pieces(inputs);
  ASSERT_EQ(pieces.size(), 4u);  // the mesh, then one piece per mesh entry of the assembly
  EXPECT_TRUE(std::filesystem::equivalent(pieces[1].file(), files.folder / "boards" / "u7.off"));
  EXPECT_EQ(pieces[1].copies(), 4u);
  EXPECT_EQ(pieces[2].copies(), 2u);
  EXPECT_EQ(pieces[3].copies(), 1u);
  TriangleSoup joined;
  for (const InputPiece& piece : pieces) {
    const TriangleSoup soup = load_input_piece(piece);
    EXPECT_LE(soup.triangle_count(), piece.copies() * 4);  // one file, placed: no sub-assembly
    joined.append(soup);
  }
  EXPECT_EQ(joined.vertices, all.vertices);
  EXPECT_EQ(joined.triangles, all.triangles);
  EXPECT_EQ(joined.part_of, all.part_of);
  EXPECT_EQ(joined.part_names, all.part_names);
  ASSERT_EQ(joined.part_count(), all.part_count());
  for (std::size_t p = 0; p < all.part_count(); ++p)
    EXPECT_EQ(joined.part_path(p), all.part_path(p));
}

TEST(Manifest, AFileDeclaringItsUnitIsConvertedUnlessThePartGivesUnits) {
  ManifestPart part;
  part.file = "board.step";
  EXPECT_EQ(part_unit_scale(part, "m", ""), 1.0);  // the file says nothing: the manifest's unit
  EXPECT_DOUBLE_EQ(part_unit_scale(part, "m", "mm"), metres_per_unit("mm"));
  EXPECT_DOUBLE_EQ(part_unit_scale(part, "in", "mm"),
                   metres_per_unit("mm") / metres_per_unit("in"));
  EXPECT_EQ(part_unit_scale(part, "mm", "mm"), 1.0);
  expect_error<InputError>([&] { part_unit_scale(part, "m", "furlong"); },
                           {"board.step", "'furlong'", "units"});
  // The part's own "units" win over the file's.
  const auto folder = scratch_folder("units");
  write_file(folder / "frame.obj", "v 0 0 0\nv 2 0 0\nv 0 2 0\nf 1 2 3\n");
  write_file(folder / "a.json",
             R"({"units": "mm", "parts": [{"file": "frame.obj", "units": "cm"}]})");
  const Manifest manifest = read_manifest(folder / "a.json");
  EXPECT_TRUE(manifest.parts[0].units_given);
  EXPECT_EQ(part_unit_scale(manifest.parts[0], manifest.units, "in"), 10.0);
  EXPECT_EQ(load_assembly(manifest).vertices[1], (Vec3{20, 0, 0}));
}

TEST(Manifest, ACycleOfManifestsIsRefusedNamingTheChain) {
  const auto folder = scratch_folder("cycle");
  write_file(folder / "frame.obj", "v 0 0 0\nv 2 0 0\nv 0 2 0\nf 1 2 3\n");
  write_file(folder / "a.json", R"({"parts": [{"file": "frame.obj"}, {"manifest": "b.json"}]})");
  write_file(folder / "b.json", R"({"parts": [{"manifest": "./a.json"}]})");
  const std::string a = (folder / "a.json").string(), b = (folder / "b.json").string();
  expect_error<InputError>(
      [&] { read_manifest(folder / "a.json"); },
      {"includes itself", a + " -> " + b + " -> " + (folder / "./a.json").string()});
  write_file(folder / "self.json", R"({"parts": [{"manifest": "self.json"}]})");
  expect_error<InputError>([&] { read_manifest(folder / "self.json"); },
                           {"self.json: parts[0].manifest", "includes itself"});
}

TEST(Manifest, SubAssembliesNestedTooDeepAreRefusedNamingTheChain) {
  const auto folder = scratch_folder("deep");
  write_file(folder / "frame.obj", "v 0 0 0\nv 2 0 0\nv 0 2 0\nf 1 2 3\n");
  const auto level = [&](int k) { return folder / ("level" + std::to_string(k) + ".json"); };
  const auto include = [&](int k, int next) {
    write_file(level(k),
               R"({"parts": [{"manifest": "level)" + std::to_string(next) + R"(.json"}]})");
  };
  write_file(level(63), R"({"parts": [{"file": "frame.obj"}]})");
  for (int k = 0; k < 63; ++k) include(k, k + 1);
  // 64 manifests deep is allowed; one more is not.
  EXPECT_EQ(
      load_assembly(read_manifest(level(0))).part_path(0),
      "level1/level2/level3/level4/level5/level6/level7/level8/level9/level10/level11/level12/"
      "level13/level14/level15/level16/level17/level18/level19/level20/level21/level22/level23/"
      "level24/level25/level26/level27/level28/level29/level30/level31/level32/level33/level34/"
      "level35/level36/level37/level38/level39/level40/level41/level42/level43/level44/level45/"
      "level46/level47/level48/level49/level50/level51/level52/level53/level54/level55/level56/"
      "level57/level58/level59/level60/level61/level62/level63/frame");
  include(63, 64);
  write_file(level(64), R"({"parts": [{"file": "frame.obj"}]})");
  expect_error<InputError>([&] { read_manifest(level(0)); },
                           {"deeper than 64", level(0).string() + " -> " + level(1).string(),
                            level(63).string() + " -> " + level(64).string()});
}

TEST(Manifest, AMissingSubManifestNamesTheIncludingFileAndField) {
  const auto folder = scratch_folder("missing_sub");
  std::filesystem::create_directories(folder / "sub");
  write_file(folder / "top.json", R"({"parts": [{"name": "x", "manifest": "sub/mid.json"}]})");
  write_file(folder / "sub" / "mid.json", R"({"parts": [{"manifest": "gone.json"}]})");
  expect_error<IoError>([&] { read_manifest(folder / "top.json"); },
                        {(folder / "top.json").string() + ": parts[0].manifest",
                         (folder / "sub/mid.json").string() + ": parts[0].manifest",
                         (folder / "sub/gone.json").string()});
}

TEST(Manifest, SubAssembliesAreReadOnceAndTheirInstancesCapped) {
  // Each level places the next twice: 2^25 instances of the mesh, from 26 small files (read once
  // each, or the read would not end).
  const auto folder = scratch_folder("diamond");
  write_file(folder / "frame.obj", "v 0 0 0\nv 2 0 0\nv 0 2 0\nf 1 2 3\n");
  write_file(folder / "level25.json", R"({"parts": [{"file": "frame.obj"}]})");
  for (int k = 0; k < 25; ++k) {
    write_file(folder / ("level" + std::to_string(k) + ".json"),
               R"({"parts": [{"manifest": "level)" + std::to_string(k + 1) +
                   R"(.json", "instances": [{}, {"translation": [1, 0, 0]}]}]})");
  }
  EXPECT_EQ(input_pieces({folder / "level2.json"}).at(0).copies(), std::size_t(1) << 23);
  EXPECT_NO_THROW(read_manifest(folder / "level1.json"));  // 2^24: the most allowed
  expect_error<InputError>([&] { read_manifest(folder / "level0.json"); },
                           {(folder / "level0.json").string(), "more than 16777216"});
}

}  // namespace
}  // namespace tetrapage::test
