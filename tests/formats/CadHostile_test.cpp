// STEP and IGES input that must not take the process down: FIFOs, cyclic and absurdly deep
// assemblies (generated here as small Part 21 text), a reader that crashes, hangs or
// allocates without end in its child process, and the pre-scan on arbitrary bytes.

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <chrono>
#include <csignal>
#include <fstream>
#include <random>
#include <sstream>
#include <thread>

#include "../ResidentMemory.h"
#include "../tools/RunCli.h"
#include "CadIsolation.h"
#include "StepPrescan.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/MemoryUsage.h"
#include "tetrapage/formats/mesh/CadReader.h"

namespace tetrapage {
namespace {

const std::filesystem::path kOcctData = "/usr/share/opencascade/data";

std::filesystem::path fresh_folder(const std::string& name) {
  const auto folder = std::filesystem::path(TETRAPAGE_TEST_TMP) / "cad_hostile" / name;
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  return folder;
}

// A Part 21 file of `products` products, each with an empty shape representation, and one
// NEXT_ASSEMBLY_USAGE_OCCURRENCE (with its placement relation) per (parent, child) link.
std::string assembly_step(int products, const std::vector<std::pair<int, int>>& links) {
  std::ostringstream out;
  out << "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\n"
         "FILE_NAME('a.step','2024-01-01T00:00:00',(''),(''),'','','');\n"
         "FILE_SCHEMA(('AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }'));\nENDSEC;\nDATA;\n"
         "#1=APPLICATION_CONTEXT('automotive design');\n"
         "#2=PRODUCT_CONTEXT('',#1,'mechanical');\n"
         "#3=PRODUCT_DEFINITION_CONTEXT('part definition',#1,'design');\n"
         "#4=(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT(.MILLI.,.METRE.));\n"
         "#5=(NAMED_UNIT(*)PLANE_ANGLE_UNIT()SI_UNIT($,.RADIAN.));\n"
         "#6=(NAMED_UNIT(*)SI_UNIT($,.STERADIAN.)SOLID_ANGLE_UNIT());\n"
         "#7=UNCERTAINTY_MEASURE_WITH_UNIT(LENGTH_MEASURE(1.E-07),#4,'distance_accuracy_value','');"
         "\n"
         "#8=(GEOMETRIC_REPRESENTATION_CONTEXT(3)GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT((#7))"
         "GLOBAL_UNIT_ASSIGNED_CONTEXT((#4,#5,#6))REPRESENTATION_CONTEXT('',''));\n"
         "#9=CARTESIAN_POINT('',(0.,0.,0.));\n#10=DIRECTION('',(0.,0.,1.));\n"
         "#11=DIRECTION('',(1.,0.,0.));\n#12=AXIS2_PLACEMENT_3D('',#9,#10,#11);\n";
  const auto product = [](int i) { return 100 + 10 * i; };  // #p: PRODUCT ... #p+5
  for (int i = 0; i < products; ++i) {
    const int p = product(i);
    out << '#' << p << "=PRODUCT('P" << i << "','P" << i << "','',(#2));\n"
        << '#' << p + 1 << "=PRODUCT_DEFINITION_FORMATION('','',#" << p << ");\n"
        << '#' << p + 2 << "=PRODUCT_DEFINITION('design','',#" << p + 1 << ",#3);\n"
        << '#' << p + 3 << "=PRODUCT_DEFINITION_SHAPE('','',#" << p + 2 << ");\n"
        << '#' << p + 4 << "=SHAPE_REPRESENTATION('',(#12),#8);\n"
        << '#' << p + 5 << "=SHAPE_DEFINITION_REPRESENTATION(#" << p + 3 << ",#" << p + 4 << ");\n";
  }
  int n = 100 + 10 * products;
  for (const auto& [parent, child] : links) {
    out << '#' << n << "=NEXT_ASSEMBLY_USAGE_OCCURRENCE('" << n << "','','',#"
        << product(parent) + 2 << ",#" << product(child) + 2 << ",$);\n"
        << '#' << n + 1 << "=PRODUCT_DEFINITION_SHAPE('','',#" << n << ");\n"
        << '#' << n + 2 << "=ITEM_DEFINED_TRANSFORMATION('','',#12,#12);\n"
        << '#' << n + 3 << "=(REPRESENTATION_RELATIONSHIP('','',#" << product(child) + 4 << ",#"
        << product(parent) + 4 << ")REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION(#" << n + 2
        << ")SHAPE_REPRESENTATION_RELATIONSHIP());\n"
        << '#' << n + 4 << "=CONTEXT_DEPENDENT_SHAPE_REPRESENTATION(#" << n + 3 << ",#" << n + 1
        << ");\n";
    n += 5;
  }
  out << "ENDSEC;\nEND-ISO-10303-21;\n";
  return out.str();
}

std::vector<std::pair<int, int>> chain(int products) {
  std::vector<std::pair<int, int>> links;
  for (int i = 0; i + 1 < products; ++i) links.push_back({i, i + 1});
  return links;
}

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

detail::StepStructure scan_text(const std::string& text) {
  detail::StepScanner scanner;
  scanner.feed(text);
  return scanner.finish();
}

// One line on stderr naming the file, exit status 1, nothing else left in the folder.
void expect_refused(const test::CliResult& result, const std::string& file,
                    const std::string& what) {
  EXPECT_EQ(result.status, 1) << result.err;
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  EXPECT_NE(result.err.find(file), std::string::npos) << result.err;
  EXPECT_NE(result.err.find(what), std::string::npos) << result.err;
}

TEST(CadHostile, AFifoIsRefusedBeforeItIsOpened) {
  const auto folder = fresh_folder("fifo");
  for (const std::string name : {"f.step", "f.igs"}) {
    ASSERT_EQ(::mkfifo((folder / name).c_str(), 0600), 0);
    expect_refused(test::run_cli_in(folder, "mesh info " + name, 30), name, "FIFO");
  }
}

TEST(CadHostile, TheScanFindsACycleOfThreeProducts) {
  const auto structure = scan_text(assembly_step(3, {{0, 1}, {1, 2}, {2, 0}}));
  EXPECT_NE(structure.cycle.find("#"), std::string::npos);
  EXPECT_EQ(structure.assembly_occurrences, 3u);
  EXPECT_THROW(detail::check_step_structure("c.step", structure, 0), InputError);
}

TEST(CadHostile, TheScanMeasuresTheDepthOfAChain) {
  for (const int products : {1, 2, 7, 300}) {
    const auto structure = scan_text(assembly_step(products, chain(products)));
    EXPECT_TRUE(structure.cycle.empty()) << structure.cycle;
    EXPECT_EQ(structure.assembly_depth, products - 1);
    EXPECT_EQ(structure.representation_depth, products - 1);
    EXPECT_EQ(structure.assembly_occurrences, std::uint64_t(products - 1));
  }
  // A product used twice by one parent, and a diamond, are no cycle.
  EXPECT_TRUE(scan_text(assembly_step(4, {{0, 1}, {0, 1}, {0, 2}, {1, 3}, {2, 3}})).cycle.empty());
}

TEST(CadHostile, TheScanReadsTheSameInPiecesOfAnySize) {
  const std::string text = assembly_step(20, {{0, 1}, {1, 2}, {2, 3}, {3, 1}, {5, 6}});
  const auto whole = scan_text(text);
  for (const std::size_t piece : {1, 2, 3, 7, 64}) {
    detail::StepScanner scanner;
    for (std::size_t at = 0; at < text.size(); at += piece)
      scanner.feed(std::string_view(text).substr(at, piece));
    const auto pieces = scanner.finish();
    EXPECT_EQ(pieces.cycle, whole.cycle) << piece;
    EXPECT_EQ(pieces.instances, whole.instances) << piece;
    EXPECT_EQ(pieces.assembly_depth, whole.assembly_depth) << piece;
  }
}

TEST(CadHostile, StringsAndCommentsAreNotEntities) {
  const std::string text =
      "DATA;\n#1=PRODUCT_DEFINITION('a;#9=NEXT_ASSEMBLY_USAGE_OCCURRENCE(''','',#2,#3);\n"
      "/* #5=NEXT_ASSEMBLY_USAGE_OCCURRENCE('','','',#1,#1,$); */\n"
      "#6=NEXT_ASSEMBLY_USAGE_OCCURRENCE('it''s','','',#1,#7,$);\nENDSEC;\n";
  const auto structure = scan_text(text);
  EXPECT_EQ(structure.instances, 2u);
  EXPECT_EQ(structure.assembly_occurrences, 1u);
  EXPECT_TRUE(structure.cycle.empty());
  EXPECT_EQ(structure.assembly_depth, 1);
}

TEST(CadHostile, TheScanSurvivesArbitraryBytes) {
  std::mt19937_64 random(35);
  const std::string alphabet = "#=();,'/*\" \n0123456789AEN_XYZ$.";
  for (int round = 0; round < 200; ++round) {
    std::string text(std::size_t(random() % 4096), '\0');
    for (char& c : text) c = round % 2 ? char(random()) : alphabet[random() % alphabet.size()];
    const auto structure = scan_text(text);
    EXPECT_LE(structure.assembly_occurrences, text.size()) << "seed 35, round " << round;
  }
}

TEST(CadHostile, OcctSamplesPassTheScan) {
  for (const char* name : {"screw.step", "linkrods.step"}) {
    const auto path = kOcctData / "step" / name;
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not installed";
    const auto structure = detail::scan_step_structure(path);
    EXPECT_TRUE(structure.cycle.empty()) << name << ": " << structure.cycle;
    EXPECT_GT(structure.instances, 100u) << name;
    EXPECT_NO_THROW(detail::check_step_structure(path, structure, 10000)) << name;
  }
}

TEST(CadHostile, ACyclicAssemblyIsRefusedByEveryCommand) {
  const auto folder = fresh_folder("cycle");
  write_text(folder / "cycle.step", assembly_step(3, {{0, 1}, {1, 2}, {2, 0}}));
  expect_refused(test::run_cli_in(folder, "mesh info cycle.step", 120), "cycle.step", "cyclic");
  expect_refused(test::run_cli_in(folder, "preprocess cycle.step -o model.tpi", 120), "cycle.step",
                 "cyclic");
  EXPECT_FALSE(std::filesystem::exists(folder / "model.tpi"));
}

TEST(CadHostile, AChainOfFiveThousandSubAssembliesIsRefused) {
  const auto folder = fresh_folder("deep");
  write_text(folder / "deep.step", assembly_step(5000, chain(5000)));
  expect_refused(test::run_cli_in(folder, "mesh info deep.step", 120), "deep.step", "nested");
  expect_refused(test::run_cli_in(folder, "preprocess deep.step -o model.tpi", 120), "deep.step",
                 "nested");
  EXPECT_FALSE(std::filesystem::exists(folder / "model.tpi"));
}

// The reading child inherits the command's unwritten stdout and OCCT writes to stdout: piped,
// `mesh info` of three CAD files printed the first file's lines three times, the second's twice.
TEST(CadHostile, TheReadingChildLeavesTheCommandsOutputAlone) {
  const auto folder = fresh_folder("stdout");
  const auto screw = kOcctData / "step" / "screw.step", bearing = kOcctData / "iges" / "bearing.iges";
  if (!std::filesystem::exists(screw) || !std::filesystem::exists(bearing))
    GTEST_SKIP() << "occt-misc not installed";
  const test::CliResult result = test::run_cli_in(
      folder, "mesh info " + screw.string() + " " + bearing.string() + " " + screw.string(), 120);
  ASSERT_EQ(result.status, 0) << result.err;
  const auto count = [&](const std::string& line) {
    std::size_t found = 0;
    for (std::size_t at = result.out.find(line); at != std::string::npos; at = result.out.find(line, at + 1))
      ++found;
    return found;
  };
  EXPECT_EQ(count(screw.string() + ": step,"), 2u) << result.out;
  EXPECT_EQ(count(bearing.string() + ": iges,"), 1u) << result.out;
}

TEST(CadHostile, TooManyOccurrencesAreRefusedWithTheLimitToRaise) {
  const auto folder = fresh_folder("occurrences");
  std::vector<std::pair<int, int>> copies;
  for (int i = 0; i < 5; ++i) copies.push_back({0, 1});
  write_text(folder / "copies.step", assembly_step(2, copies));
  TessellationOptions options;
  options.max_occurrences = 4;
  try {
    read_cad(folder / "copies.step", options);
    ADD_FAILURE() << "read";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("5 part occurrences"), std::string::npos)
        << error.what();
  }
  expect_refused(test::run_cli_in(folder, "mesh info copies.step --max-cad-occurrences 4", 120),
                 "copies.step", "--max-cad-occurrences");
}

// A deflection far finer than the default is refused by its estimate before the mesher runs
// (a 40 mm screw at 1e-6 mm once took gigabytes and minutes); the limit can be raised.
TEST(CadHostile, AHugeTessellationIsRefusedByItsEstimate) {
  const auto folder = fresh_folder("estimate");
  const auto start = std::chrono::steady_clock::now();
  const test::CliResult refused =
      test::run_cli_in(folder, "mesh info " + (kOcctData / "step" / "screw.step").string() + " --deflection 1e-6", 120);
  EXPECT_EQ(refused.status, 1) << refused.err;
  EXPECT_NE(refused.err.find("--max-cad-triangles"), std::string::npos) << refused.err;
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(100)) << "refused before tessellating";
  TessellationOptions options;
  options.deflection = 1e-6;
  options.relative_deflection = false;
  options.max_triangles = 1000;
  EXPECT_THROW(read_cad(kOcctData / "step" / "screw.step", options), InputError);
}

// Within the triangle limit, OCCT's mesher holds 3 KB and more a triangle of a finely meshed
// face (a 10 mm sphere at 4e-5 mm grew past 21 GB): a deflection whose mesher would exceed
// --cad-memory is refused by its estimate, before the mesher runs.
TEST(CadHostile, AMesherBeyondTheReadingsMemoryIsRefusedByItsEstimate) {
  const auto folder = fresh_folder("mesher-memory");
  const auto screw = kOcctData / "step" / "screw.step";
  if (!std::filesystem::exists(screw)) GTEST_SKIP() << screw << " not installed";
  const auto start = std::chrono::steady_clock::now();
  const test::CliResult refused = test::run_cli_in(
      folder, "mesh info " + screw.string() + " --deflection 1e-4 --cad-memory 512M", 120);
  EXPECT_EQ(refused.status, 1) << refused.err;
  EXPECT_NE(refused.err.find("screw.step"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("mesher needs about"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("--cad-memory"), std::string::npos) << refused.err;
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(60)) << "refused before meshing";
  TessellationOptions options;
  options.deflection = 1e-4;
  options.relative_deflection = false;
  options.memory_limit = std::uint64_t(512) << 20;
  EXPECT_THROW(read_cad(screw, options), InputError);
}

// Reading the same STEP and IGES files again and again leaves the caller's resident memory
// flat: what OpenCASCADE keeps (its caches, the leaks LSan reports in its libraries) stays in
// the child, and our side of the read keeps nothing.
TEST(CadHostile, RepeatedReadsKeepTheCallersMemoryFlat) {
  // Under ASan the quarantine of freed blocks grew 70 MiB over these reads; LeakSanitizer
  // checks them for leaks there.
  if (!test::kResidentMemoryIsTheProgramsOwn) {
    GTEST_SKIP() << "resident memory is ASan's too";
  }
  const std::vector<std::filesystem::path> files = {kOcctData / "step" / "screw.step",
                                                    kOcctData / "iges" / "hammer.iges"};
  for (const auto& file : files) (void)read_cad(file);  // allocators warmed up
  const std::uint64_t before = resident_bytes();
  for (int round = 0; round < 40; ++round)
    for (const auto& file : files) EXPECT_GT(read_cad(file).triangle_count(), 0u);
  const std::uint64_t after = resident_bytes();
  EXPECT_LT(after, before + (std::uint64_t(8) << 20)) << before << " -> " << after << " bytes resident";
}

// The child process: whatever its reader does, the caller gets an Error and no zombie.
void expect_no_child_left() {
  int status = 0;
  EXPECT_EQ(::waitpid(-1, &status, WNOHANG), -1);
  EXPECT_EQ(errno, ECHILD);
}

TEST(CadHostile, AReaderThatCrashesBecomesAnErrorNamingTheFile) {
  try {
    detail::read_in_child("x.step", {}, []() -> detail::CadContent {
      std::raise(SIGSEGV);
      return {};
    });
    ADD_FAILURE() << "no error";
  } catch (const FormatError& error) {
    EXPECT_STREQ(error.what(), "reading 'x.step' crashed OpenCASCADE (signal 11)");
  }
  expect_no_child_left();
}

TEST(CadHostile, AReaderThatHangsIsStoppedAtTheTimeLimit) {
  detail::IsolationLimits limits;
  limits.seconds = 1;
  try {
    detail::read_in_child("x.step", limits, []() -> detail::CadContent {
      for (;;) std::this_thread::sleep_for(std::chrono::seconds(1));
    });
    ADD_FAILURE() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("took longer than 1 s"), std::string::npos)
        << error.what();
  }
  expect_no_child_left();
}

TEST(CadHostile, AReaderThatAllocatesWithoutEndMeetsTheMemoryLimit) {
  if (!detail::memory_limit_applies()) GTEST_SKIP() << "no address-space limit under a sanitizer";
  detail::IsolationLimits limits;
  limits.memory_bytes = std::uint64_t(256) << 20;
  try {
    detail::read_in_child("x.step", limits, []() -> detail::CadContent {
      std::vector<std::vector<char>> blocks;
      for (;;) blocks.emplace_back(std::size_t(64) << 20, 'x');
    });
    ADD_FAILURE() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("more memory than its limit of 256 MiB"),
              std::string::npos)
        << error.what();
  }
  expect_no_child_left();
}

TEST(CadHostile, TheReadersErrorComesBackWithItsClassAndMessage) {
  EXPECT_THROW(detail::read_in_child("x.step", {},
                                     []() -> detail::CadContent { throw InputError("x: bad"); }),
               InputError);
  try {
    detail::read_in_child("x.step", {},
                          []() -> detail::CadContent { throw FormatError("x: worse"); });
  } catch (const FormatError& error) {
    EXPECT_STREQ(error.what(), "x: worse");
  }
  expect_no_child_left();
}

TEST(CadHostile, AChildReadGivesTheSameSoupAsAnInProcessRead) {
  for (const std::filesystem::path& path :
       {kOcctData / "step" / "screw.step", kOcctData / "iges" / "hammer.iges"}) {
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not installed";
    TessellationOptions options;
    options.isolate = false;
    ReadReport here_report, child_report;
    const TriangleSoup here = read_cad(path, options, &here_report);
    options.isolate = true;
    const TriangleSoup child = read_cad(path, options, &child_report);
    EXPECT_EQ(here.vertices, child.vertices) << path;
    EXPECT_EQ(here.triangles, child.triangles) << path;
    EXPECT_EQ(here.part_of, child.part_of) << path;
    EXPECT_EQ(here_report.tessellation_deflection, child_report.tessellation_deflection) << path;
    EXPECT_EQ(here_report.format, child_report.format) << path;
    expect_no_child_left();
  }
}

}  // namespace
}  // namespace tetrapage
