// The STEP and IGES reader against OpenCASCADE's own exact measures of the B-rep (bounding box
// and area computed from the surfaces, not from any triangulation), and against assemblies
// this test writes itself through OCCT's XCAF writer, whose placements and names it knows.

#include <BRepBndLib.hxx>
#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakeWire.hxx>
#include <BRepGProp.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <Bnd_Box.hxx>
#include <GProp_GProps.hxx>
#include <IGESControl_Reader.hxx>
#include <Interface_Static.hxx>
#include <STEPCAFControl_Writer.hxx>
#include <STEPControl_Reader.hxx>
#include <TDataStd_Name.hxx>
#include <TDocStd_Document.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <gp_Quaternion.hxx>
#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>

#include "TestSupport.h"
#include "tetrapage/formats/mesh/CadReader.h"
#include "tetrapage/formats/mesh/MeshReader.h"

namespace tetrapage {
namespace {

const std::filesystem::path kOcctData = "/usr/share/opencascade/data";
const std::filesystem::path kFreecadIdf = "/usr/share/freecad/Mod/Idf/Idflibs";

TopoDS_Shape exact_shape(const std::filesystem::path& path) {
  const std::string extension = path.extension().string();
  if (extension == ".iges" || extension == ".igs") {
    IGESControl_Reader reader;
    EXPECT_EQ(reader.ReadFile(path.string().c_str()), IFSelect_RetDone);
    reader.TransferRoots();
    return reader.OneShape();
  }
  STEPControl_Reader reader;
  EXPECT_EQ(reader.ReadFile(path.string().c_str()), IFSelect_RetDone);
  reader.TransferRoots();
  return reader.OneShape();
}

double soup_area(const TriangleSoup& soup) {
  double area = 0;
  for (std::size_t t = 0; t < soup.triangles.size(); ++t) {
    const auto [a, b, c] = soup.corners(t);
    const Vec3 u{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    area += 0.5 * std::hypot(u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                             u[0] * v[1] - u[1] * v[0]);
  }
  return area;
}

// Every edge (a pair of corner positions) used an even number of times: a closed surface.
bool every_edge_paired(const TriangleSoup& soup) {
  std::map<std::pair<Vec3, Vec3>, int> uses;
  for (std::size_t t = 0; t < soup.triangles.size(); ++t) {
    const auto corners = soup.corners(t);
    for (int k = 0; k < 3; ++k) {
      Vec3 p = corners[k], q = corners[(k + 1) % 3];
      if (q < p) std::swap(p, q);
      ++uses[{p, q}];
    }
  }
  return std::all_of(uses.begin(), uses.end(), [](const auto& use) { return use.second % 2 == 0; });
}

struct SampleCase {
  std::filesystem::path path;
  bool closed;
};

class CadSamples : public ::testing::TestWithParam<SampleCase> {};

TEST_P(CadSamples, TessellationLiesWithinTheDeflectionOfTheExactShape) {
  const auto& sample = GetParam();
  if (!std::filesystem::exists(sample.path)) GTEST_SKIP() << sample.path << " not installed";
  ReadReport report;
  const TriangleSoup soup = read_cad(sample.path, {}, &report);
  const TopoDS_Shape shape = exact_shape(sample.path);
  Bnd_Box exact;
  BRepBndLib::AddOptimal(shape, exact, Standard_False, Standard_False);
  double lo[3], hi[3];
  exact.Get(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
  const double deflection = report.tessellation_deflection;
  ASSERT_GT(deflection, 0);
  EXPECT_EQ(report.length_unit, "mm");
  const BoundingBox box = soup.bounds();
  const double diagonal = std::hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  // Vertices lie on the surfaces (up to OCCT's tolerances), and no face is farther than the
  // deflection from the triangles.
  const double slack = 1e-6 * diagonal;
  for (int a = 0; a < 3; ++a) {
    EXPECT_GE(box.lo[a], lo[a] - slack) << sample.path;
    EXPECT_LE(box.hi[a], hi[a] + slack) << sample.path;
    EXPECT_LE(box.lo[a], lo[a] + deflection + slack) << sample.path;
    EXPECT_GE(box.hi[a], hi[a] - deflection - slack) << sample.path;
  }
  GProp_GProps properties;
  BRepGProp::SurfaceProperties(shape, properties);
  EXPECT_NEAR(soup_area(soup), properties.Mass(), 0.01 * properties.Mass()) << sample.path;
  if (sample.closed) {
    EXPECT_TRUE(every_edge_paired(soup)) << sample.path;
  }
  EXPECT_EQ(soup.part_of.size(), soup.triangles.size());
}

INSTANTIATE_TEST_SUITE_P(OcctAndFreecadSamples, CadSamples,
                         ::testing::Values(SampleCase{kOcctData / "step" / "screw.step", true},
                                           SampleCase{kOcctData / "step" / "linkrods.step", true},
                                           SampleCase{kOcctData / "iges" / "bearing.iges", false},
                                           SampleCase{kFreecadIdf / "SOT23.stp", false},
                                           SampleCase{kFreecadIdf / "0603_SMD.stp", false}));

TEST(CadReader, AFinerDeflectionGivesMoreTrianglesCloserToTheArea) {
  const auto path = kOcctData / "step" / "screw.step";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not installed";
  GProp_GProps properties;
  BRepGProp::SurfaceProperties(exact_shape(path), properties);
  TessellationOptions coarse, fine;
  coarse.deflection = 0.01;
  fine.deflection = 0.0005;
  ReadReport coarse_report, fine_report;
  const TriangleSoup coarse_soup = read_cad(path, coarse, &coarse_report);
  const TriangleSoup fine_soup = read_cad(path, fine, &fine_report);
  EXPECT_GT(fine_soup.triangle_count(), coarse_soup.triangle_count());
  EXPECT_LT(fine_report.tessellation_deflection, coarse_report.tessellation_deflection);
  EXPECT_LT(std::fabs(soup_area(fine_soup) - properties.Mass()),
            std::fabs(soup_area(coarse_soup) - properties.Mass()));
  // An absolute deflection is used as given.
  TessellationOptions absolute;
  absolute.relative_deflection = false;
  absolute.deflection = 0.05;
  ReadReport absolute_report;
  read_cad(path, absolute, &absolute_report);
  EXPECT_DOUBLE_EQ(absolute_report.tessellation_deflection, 0.05);
}

// An assembly written by OCCT's XCAF writer: a rack of two boards, each with a box part "U7"
// placed twice and a cylinder "J1" once, in the given STEP unit.
struct WrittenAssembly {
  std::filesystem::path path;
  std::vector<gp_Trsf> box_placements;  // world placements of the box instances, in mm
};

TDF_Label add_named(const Handle(XCAFDoc_ShapeTool) & tool, const TopoDS_Shape& shape,
                    const char* name) {
  const TDF_Label label = tool->AddShape(shape, Standard_False);
  TDataStd_Name::Set(label, name);
  return label;
}

gp_Trsf placement(double angle, double x, double y, double z) {
  gp_Trsf t;
  t.SetRotation(gp_Quaternion(gp_Vec(0, 0, 1), angle));
  t.SetTranslationPart(gp_Vec(x, y, z));
  return t;
}

WrittenAssembly write_rack(const std::filesystem::path& folder, const char* unit) {
  Handle(TDocStd_Document) document;
  XCAFApp_Application::GetApplication()->NewDocument("MDTV-XCAF", document);
  const Handle(XCAFDoc_ShapeTool) tool = XCAFDoc_DocumentTool::ShapeTool(document->Main());
  const TDF_Label box = add_named(tool, BRepPrimAPI_MakeBox(10, 20, 5).Shape(), "CHIP_10x20");
  const TDF_Label cylinder = add_named(tool, BRepPrimAPI_MakeCylinder(3, 8).Shape(), "CONN");
  const TDF_Label board = tool->NewShape();
  TDataStd_Name::Set(board, "board");
  const gp_Trsf u7_a = placement(0, 5, 5, 0), u7_b = placement(M_PI / 2, 60, 5, 0);
  TDataStd_Name::Set(tool->AddComponent(board, box, TopLoc_Location(u7_a)), "U7");
  TDataStd_Name::Set(tool->AddComponent(board, box, TopLoc_Location(u7_b)), "U7");
  TDataStd_Name::Set(tool->AddComponent(board, cylinder, TopLoc_Location(placement(0, 30, 40, 0))),
                     "J1");
  tool->UpdateAssemblies();
  const TDF_Label rack = tool->NewShape();
  TDataStd_Name::Set(rack, "rack");
  const gp_Trsf board_0 = placement(0, 0, 0, 0), board_1 = placement(0, 0, 0, 100);
  TDataStd_Name::Set(tool->AddComponent(rack, board, TopLoc_Location(board_0)), "board_0");
  TDataStd_Name::Set(tool->AddComponent(rack, board, TopLoc_Location(board_1)), "board_1");
  tool->UpdateAssemblies();
  Interface_Static::SetCVal("write.step.unit", unit);
  STEPCAFControl_Writer writer;
  WrittenAssembly written{folder / (std::string("rack_") + unit + ".step"), {}};
  EXPECT_TRUE(writer.Transfer(document, STEPControl_AsIs));
  EXPECT_EQ(writer.Write(written.path.string().c_str()), IFSelect_RetDone);
  Interface_Static::SetCVal("write.step.unit", "MM");
  XCAFApp_Application::GetApplication()->Close(document);
  for (const gp_Trsf& b : {board_0, board_1})
    for (const gp_Trsf& u : {u7_a, u7_b}) written.box_placements.push_back(b * u);
  return written;
}

TEST(CadReader, AnAssemblyGivesEveryInstanceWithItsNamePathAndPlacement) {
  const auto folder = test::scratch_folder("rack");
  const WrittenAssembly written = write_rack(folder, "MM");
  ReadReport report;
  const TriangleSoup soup = read_cad(written.path, {}, &report);
  ASSERT_EQ(soup.part_count(), 6u);  // two boards of three instances
  std::set<std::string> paths;
  std::vector<std::uint32_t> boxes;
  for (std::uint32_t p = 0; p < soup.part_count(); ++p) {
    paths.insert(soup.part_path(p));
    if (soup.part_names[p] == "CHIP_10x20") boxes.push_back(p);
  }
  EXPECT_EQ(paths,
            (std::set<std::string>{"rack/board_0/U7#0", "rack/board_0/U7#1", "rack/board_0/J1",
                                   "rack/board_1/U7#0", "rack/board_1/U7#1", "rack/board_1/J1"}));
  ASSERT_EQ(boxes.size(), 4u);
  // Each box instance's vertices are the box's corners moved by the placement we wrote.
  for (std::size_t k = 0; k < boxes.size(); ++k) {
    std::set<std::array<long, 3>> expected, got;
    for (double x : {0.0, 10.0})
      for (double y : {0.0, 20.0})
        for (double z : {0.0, 5.0}) {
          const gp_Pnt p = gp_Pnt(x, y, z).Transformed(written.box_placements[k]);
          expected.insert(
              {std::lround(p.X() * 1e6), std::lround(p.Y() * 1e6), std::lround(p.Z() * 1e6)});
        }
    for (std::size_t t = 0; t < soup.triangles.size(); ++t) {
      if (soup.part_of[t] != boxes[k]) continue;
      for (const Vec3& c : soup.corners(t))
        got.insert({std::lround(c[0] * 1e6), std::lround(c[1] * 1e6), std::lround(c[2] * 1e6)});
    }
    EXPECT_EQ(got, expected) << soup.part_path(boxes[k]);
  }
}

// The instances of a STEP or IGES file placed a chunk at a time (read_mesh_in_chunks, for an
// assembly too large to hold placed) are the whole read's: the same corners, parts, paths and
// report, every placed vertex given to on_vertex, no chunk larger than asked, and a chunk's
// vertices only those its triangles use. OCCT's samples, FreeCAD's IDF parts (open shells) and
// the written rack (each instance of a shape placed from the one tessellation), in chunks of 1,
// 7 and 1000.
TEST(CadReader, InstancesPlacedInChunksAreTheWholeRead) {
  const auto folder = test::scratch_folder("chunks");
  std::vector<std::filesystem::path> files = {write_rack(folder, "MM").path,
                                              write_rack(folder, "M").path};
  for (const auto& sample : {kOcctData / "step" / "linkrods.step", kOcctData / "step" / "screw.step",
                             kOcctData / "iges" / "bearing.iges", kFreecadIdf / "SOT23.stp",
                             kFreecadIdf / "0603_SMD.stp"})
    if (std::filesystem::exists(sample)) files.push_back(sample);
  for (const auto& file : files) {
    ReadReport whole_report;
    const TriangleSoup whole = read_mesh(file, &whole_report);
    for (const std::size_t size : {std::size_t(1), std::size_t(7), std::size_t(1000)}) {
      SCOPED_TRACE(file.filename().string() + ", chunks of " + std::to_string(size));
      test::HandedOver handed;
      std::vector<Vec3> noted;
      SoupChunks chunks;
      chunks.triangles = size;
      chunks.on_vertex = [&](const Vec3& vertex) { noted.push_back(vertex); };
      chunks.take = [&](TriangleSoup&& chunk) {
        EXPECT_LE(chunk.triangle_count(), size);
        EXPECT_GT(chunk.triangle_count(), 0u);
        EXPECT_EQ(chunk.part_of.size(), chunk.triangle_count());
        std::vector<bool> used(chunk.vertices.size(), false);
        for (const TriangleIndices& t : chunk.triangles)
          for (const std::uint32_t v : t) used.at(v) = true;
        EXPECT_EQ(std::count(used.begin(), used.end(), false), 0);
        handed.add(chunk);
      };
      ReadReport report;
      const TriangleSoup names = read_mesh_in_chunks(file, &report, chunks);
      test::expect_whole_read(names, handed, whole);
      EXPECT_EQ(noted, whole.vertices);
      EXPECT_EQ(report.triangles_read, whole_report.triangles_read);
      EXPECT_EQ(report.degenerate_dropped, whole_report.degenerate_dropped);
      EXPECT_EQ(report.tessellation_deflection, whole_report.tessellation_deflection);
      EXPECT_EQ(report.length_unit, "mm");
      EXPECT_EQ(report.format, whole_report.format);
      EXPECT_EQ(report.bytes, whole_report.bytes);
    }
  }
}

TEST(CadReader, UnitsOfTheFileComeBackAsMillimetres) {
  const auto folder = test::scratch_folder("units");
  const TriangleSoup reference = read_cad(write_rack(folder, "MM").path);
  for (const char* unit : {"INCH", "M"}) {
    ReadReport report;
    const TriangleSoup soup = read_cad(write_rack(folder, unit).path, {}, &report);
    EXPECT_EQ(report.length_unit, "mm");
    ASSERT_EQ(soup.triangle_count(), reference.triangle_count()) << unit;
    const BoundingBox a = soup.bounds(), b = reference.bounds();
    for (int axis = 0; axis < 3; ++axis) {
      EXPECT_NEAR(a.lo[axis], b.lo[axis], 1e-6) << unit;
      EXPECT_NEAR(a.hi[axis], b.hi[axis], 1e-6) << unit;
    }
  }
}

// A file with a shape the mesher cannot tessellate (a face bounded by an open wire) beside a
// good one.
std::filesystem::path write_with_bad_part(const std::filesystem::path& folder) {
  Handle(TDocStd_Document) document;
  XCAFApp_Application::GetApplication()->NewDocument("MDTV-XCAF", document);
  const Handle(XCAFDoc_ShapeTool) tool = XCAFDoc_DocumentTool::ShapeTool(document->Main());
  add_named(tool, BRepPrimAPI_MakeBox(10, 20, 5).Shape(), "GOOD");
  BRepBuilderAPI_MakeWire open_wire;
  open_wire.Add(BRepBuilderAPI_MakeEdge(gp_Pnt(0, 0, 0), gp_Pnt(10, 0, 0)).Edge());
  open_wire.Add(BRepBuilderAPI_MakeEdge(gp_Pnt(10, 0, 0), gp_Pnt(10, 10, 0)).Edge());
  add_named(tool,
            BRepBuilderAPI_MakeFace(gp_Pln(gp::Origin(), gp::DZ()), open_wire.Wire(), Standard_True)
                .Shape(),
            "OPEN_FACE");
  STEPCAFControl_Writer writer;
  const auto path = folder / "bad_part.step";
  EXPECT_TRUE(writer.Transfer(document, STEPControl_AsIs));
  EXPECT_EQ(writer.Write(path.string().c_str()), IFSelect_RetDone);
  XCAFApp_Application::GetApplication()->Close(document);
  return path;
}

TEST(CadReader, APartThatFailsToTessellateIsNamedOrSkipped) {
  const auto path = write_with_bad_part(test::scratch_folder("bad"));
  try {
    read_cad(path);
    ADD_FAILURE() << "read";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("OPEN_FACE"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("--skip-bad-parts"), std::string::npos)
        << error.what();
  }
  TessellationOptions skip;
  skip.skip_bad_parts = true;
  ReadReport report;
  const TriangleSoup soup = read_cad(path, skip, &report);
  ASSERT_EQ(report.skipped_parts.size(), 1u);
  EXPECT_NE(report.skipped_parts[0].find("OPEN_FACE"), std::string::npos)
      << report.skipped_parts[0];
  ASSERT_EQ(soup.part_count(), 1u);
  EXPECT_EQ(soup.part_names[0], "GOOD");
  EXPECT_EQ(soup.triangle_count(), 12u);  // a box's six faces, two triangles each
}

// A shape that fails to tessellate, skipped, is skipped alike when the instances are placed in
// chunks: the same parts, triangles and list of skipped parts; not skipped, both reads fail.
TEST(CadReader, ABadPartPlacedInChunksIsSkippedOrRefusedAsWhole) {
  const auto path = write_with_bad_part(test::scratch_folder("bad_chunks"));
  test::HandedOver handed;
  SoupChunks chunks;
  chunks.triangles = 5;
  chunks.take = [&](TriangleSoup&& chunk) { handed.add(chunk); };
  EXPECT_THROW(read_mesh_in_chunks(path, nullptr, chunks), InputError);
  handed = {};
  TessellationOptions skip;
  skip.skip_bad_parts = true;
  ReadReport whole_report, report;
  const TriangleSoup whole = read_mesh(path, &whole_report, skip);
  const TriangleSoup names = read_mesh_in_chunks(path, &report, chunks, skip);
  test::expect_whole_read(names, handed, whole);
  EXPECT_EQ(report.skipped_parts, whole_report.skipped_parts);
  ASSERT_EQ(report.skipped_parts.size(), 1u);
}

TEST(CadReader, DamagedFilesAreRefusedNamingTheFile) {
  const auto folder = test::scratch_folder("damaged");
  const auto screw = kOcctData / "step" / "screw.step";
  if (!std::filesystem::exists(screw)) GTEST_SKIP() << screw << " not installed";
  std::ifstream in(screw, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"truncated_header.step", bytes.substr(0, 200)},
      {"garbage.step", std::string(4096, '\x7f')},
      {"empty.stp", ""},
      {"not_iges.igs", "this is not an IGES file\n"},
      {"data_only.step", "ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\nENDSEC;\nEND-ISO-10303-21;\n"},
  };
  for (const auto& [name, content] : cases) {
    const auto path = folder / name;
    test::write_file(path, content);
    try {
      read_cad(path);
      ADD_FAILURE() << name << " was read";
    } catch (const Error& error) {
      EXPECT_NE(std::string(error.what()).find(path.string()), std::string::npos) << error.what();
    }
  }
  // Cut in the middle of its entities: refused, or read as what survived (never a crash).
  const auto half = folder / "half.step";
  test::write_file(half, bytes.substr(0, bytes.size() / 2));
  try {
    const TriangleSoup soup = read_cad(half);
    EXPECT_GT(soup.triangle_count(), 0u);
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find(half.string()), std::string::npos) << error.what();
  }
  EXPECT_THROW(read_cad(folder / "missing.step"), IoError);
  TessellationOptions bad;
  bad.deflection = 0;
  EXPECT_THROW(read_cad(screw, bad), InputError);
}

}  // namespace
}  // namespace tetrapage

namespace tetrapage {
namespace {

// Whether tetrapage's CAD module is mapped into this process.
bool cad_module_mapped() {
  std::ifstream maps("/proc/self/maps");
  std::string line;
  while (std::getline(maps, line))
    if (line.find("/tetrapage_cad.so") != std::string::npos) return true;
  return false;
}

const char kTetrahedronPly[] =
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\n"
    "property double z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";

// The CAD module (OpenCASCADE, Assimp) is loaded by the first file that needs it, never by a
// program that reads only our own formats. Each case runs in a new process (the death test's
// "threadsafe" style executes the test binary again), where nothing has loaded it yet.
TEST(CadModule, IsLoadedOnlyWhenAFileNeedsIt) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const auto folder = test::scratch_folder("cad-module-loaded");
  const auto ply = folder / "tetrahedron.ply";
  test::write_file(ply, kTetrahedronPly);
  EXPECT_EXIT(
      {
        if (cad_module_mapped()) std::_Exit(1);
        if (read_mesh(ply).triangles.size() != 4 || cad_module_mapped()) std::_Exit(2);
        if (read_mesh(kOcctData / "step" / "screw.step").triangles.empty() || !cad_module_mapped())
          std::_Exit(3);
        std::_Exit(0);
      },
      ::testing::ExitedWithCode(0), "");
}

// A module that cannot be loaded is an error naming the file that needed it, where the module
// was looked for and why it failed; never a crash, and our own formats still read.
TEST(CadModule, OneThatCannotBeLoadedIsAnErrorNamingTheFileAndThePlace) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const auto folder = test::scratch_folder("cad-module-missing");
  const auto ply = folder / "tetrahedron.ply";
  test::write_file(ply, kTetrahedronPly);
  const auto screw = kOcctData / "step" / "screw.step";
  for (const auto& [module, why] : {std::pair{folder / "absent.so", std::string("not found")},
                                    std::pair{ply, std::string("invalid ELF header")}}) {
    EXPECT_EXIT(
        {
          ::setenv("TETRAPAGE_CAD_MODULE", module.c_str(), 1);
          try {
            read_mesh(screw);
          } catch (const IoError& error) {
            const std::string message = error.what();
            if (message.find("'" + screw.string() + "'") == std::string::npos ||
                message.find(module.string()) == std::string::npos ||
                message.find(why) == std::string::npos)
              std::_Exit(2);
            std::_Exit(read_mesh(ply).triangles.size() == 4 ? 0 : 3);
          }
          std::_Exit(1);
        },
        ::testing::ExitedWithCode(0), "")
        << module;
  }
}

}  // namespace
}  // namespace tetrapage
