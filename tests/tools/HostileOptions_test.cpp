// The command line's options against hostile values (tools/cli/): every numeric option states
// its range and refuses values outside it, non-finite ones and negative counts; no option takes
// an empty value; options that would do nothing and names no command or option knows are
// refused. Each is a command-line mistake: one line on stderr naming the option, exit 2, nothing
// written.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "RunCli.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/UnitQuaternion.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/tools/AnswerFile.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;

// Every command that takes options of its own, as a user types it.
const char* const kCommands[] = {"generate scene",
                                 "generate tetras",
                                 "generate terrain",
                                 "generate object",
                                 "generate rack",
                                 "generate flight",
                                 "replay",
                                 "mesh info",
                                 "mesh convert",
                                 "preprocess",
                                 "inspect",
                                 "validate",
                                 "fly",
                                 "check-interiors",
                                 "check-location",
                                 "render"};

// An option as its command's help shows it: its long name and the kind of value it takes.
struct HelpOption {
  std::string name;  // "--zoom"
  std::string type;  // "FLOAT:in [0.001, 1000]=1", "TEXT", ...
};

// The options of `command` that take a value, read from its --help.
std::vector<HelpOption> options_of(const std::string& command) {
  std::string help;
  EXPECT_EQ(test::run_cli(command + " --help", help), 0) << command;
  std::vector<HelpOption> options;
  const std::regex line_pattern(R"(^\s+(?:-\w,)?(--[\w-]+) (\S.*?)(?:  |$))");
  std::istringstream text(help);
  for (std::string line; std::getline(text, line);) {
    std::smatch match;
    if (std::regex_search(line, match, line_pattern)) options.push_back({match[1], match[2]});
  }
  return options;
}

bool is_numeric(const HelpOption& option) {
  return option.type.starts_with("FLOAT") || option.type.starts_with("INT") ||
         option.type.starts_with("UINT");
}

class HostileOptions : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_ = fs::path(TETRAPAGE_TEST_TMP) /
              ("options-" + std::to_string(::getpid()) + "-" +
               ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(folder_);
    fs::create_directories(folder_);
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(folder_, ignored);
  }
  // Under a 60 s timeout: a run that never ends fails, it never blocks the suite.
  test::CliResult run(const std::string& arguments) const {
    return test::run_cli_in(folder_, arguments, 60);
  }
  // A command-line mistake: exit 2, one line on stderr naming `what`.
  void expect_usage_error(const std::string& arguments, const std::string& what) const {
    const test::CliResult r = run(arguments);
    EXPECT_EQ(r.status, 2) << arguments << ": " << r.err;
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << arguments << ": one line: " << r.err;
    EXPECT_NE(r.err.find(what), std::string::npos) << arguments << ": " << r.err;
  }
  // A file that exists, for the options that check their file exists before the mistake.
  void touch(const std::string& name) const { std::ofstream(folder_ / name) << "x\n"; }
  // The folder holds only the files the test made.
  void expect_nothing_written(std::size_t files_made) const {
    std::size_t files = 0;
    for ([[maybe_unused]] const auto& entry : fs::directory_iterator(folder_)) ++files;
    EXPECT_EQ(files, files_made);
  }
  fs::path folder_;
};

TEST_F(HostileOptions, EveryNumericOptionStatesItsRangeAndRefusesNonFiniteValues) {
  std::size_t numeric = 0;
  for (const std::string command : kCommands) {
    for (const HelpOption& option : options_of(command)) {
      if (!is_numeric(option)) continue;
      ++numeric;
      EXPECT_TRUE(option.type.find("in [") != std::string::npos ||
                  option.type.find("in (") != std::string::npos)
          << command << " " << option.name << " shows no range: " << option.type;
      for (const char* value : {"nan", "inf", "-inf", "1e308", "abc"})
        expect_usage_error(command + " " + option.name + " " + value, option.name);
    }
  }
  // render's --zoom, --azimuth, fly's --max-distance, the seeds, counts and thread numbers...
  EXPECT_GE(numeric, 40u);
}

TEST_F(HostileOptions, EveryCountRefusesNegativeAndAbsurdValues) {
  for (const std::string command : kCommands)
    for (const HelpOption& option : options_of(command))
      if (option.type.starts_with("INT") || option.type.starts_with("UINT"))
        for (const char* value : {"-1", "1.5", "18446744073709551616", "1e30"})
          expect_usage_error(command + " " + option.name + " " + value, option.name);
  // Once they wrapped to 2^64-1 points and ran for ever, or failed in vector::reserve.
  touch("model.tpi");
  expect_usage_error("check-interiors model.tpi --points -1", "--points");
  expect_usage_error("check-location model.tpi --points -1", "--points");
  expect_usage_error("check-location model.tpi --points 1000000000000", "--points");
  expect_nothing_written(1);
}

TEST_F(HostileOptions, RenderRefusesCameraValuesOutsideTheirRange) {
  touch("model.tpi");
  expect_usage_error("render model.tpi -o view.png --zoom nan", "--zoom");
  expect_usage_error("render model.tpi -o view.png --zoom 0", "--zoom");
  expect_usage_error("render model.tpi -o view.png --azimuth inf", "--azimuth");
  expect_usage_error("render model.tpi -o view.png --elevation 1e308", "--elevation");
  expect_usage_error("render model.tpi -o view.png --elevation 91", "--elevation");
  expect_nothing_written(1);
}

TEST_F(HostileOptions, BadDeflectionsAndMemoryBudgetsAreCommandLineMistakes) {
  touch("model.ply");
  for (const char* deflection : {"abc", "0", "nan", "-1", "0%", "200%", "inf"})
    expect_usage_error(std::string("preprocess model.ply -o x.tpi --deflection ") + deflection,
                       "--deflection");
  expect_usage_error("preprocess model.ply -o x.tpi --angular-deflection 0",
                     "--angular-deflection");
  for (const char* memory : {"0", "1e-3", "15M"})
    expect_usage_error(std::string("preprocess model.ply -o x.tpi --memory ") + memory, "--memory");
  touch("model.tpi");
  touch("object.ply");
  touch("flight.csv");
  for (const char* memory : {"0", "1e-3"})
    expect_usage_error(
        std::string("fly model.tpi --object object.ply --path flight.csv --memory ") + memory,
        "--memory");
  expect_usage_error("fly model.tpi --object object.ply --path flight.csv --accuracy sloppy",
                     "--accuracy");
  expect_usage_error("fly model.tpi --object object.ply --path flight.csv --query maybe",
                     "--query");
  expect_usage_error("fly model.tpi --object object.ply --path flight.csv --object-unit furlong",
                     "--object-unit");
  expect_nothing_written(4);
}

TEST_F(HostileOptions, NoOptionTakesAnEmptyValue) {
  std::size_t options = 0;
  for (const std::string command : kCommands)
    for (const HelpOption& option : options_of(command)) {
      ++options;
      expect_usage_error(command + " " + option.name + " ''", option.name);
    }
  EXPECT_GE(options, 100u);
  // Once these wrote nothing and exited 0, or failed making an absolute path.
  touch("model.tpi");
  touch("object.ply");
  touch("flight.csv");
  const std::string fly = "fly model.tpi --object object.ply --path flight.csv ";
  expect_usage_error(fly + "--answers ''", "--answers");
  expect_usage_error(fly + "--report ''", "--report");
  expect_usage_error(fly + "--contacts ''", "--contacts");
  expect_usage_error("preprocess object.ply -o ''", "--output");
  expect_nothing_written(3);
}

TEST_F(HostileOptions, OptionsThatWouldDoNothingAreRefused) {
  touch("model.tpi");
  touch("object.ply");
  touch("flight.csv");
  const std::string fly = "fly model.tpi --object object.ply --path flight.csv ";
  expect_usage_error(fly + "--max-distance 1", "--max-distance");
  expect_usage_error(fly + "--query toi --max-distance 1", "--max-distance");
  expect_usage_error(fly + "--query distance --toi-tolerance 0.01", "--toi-tolerance");
  // An index under a name another format claims.
  for (const char* output :
       {"out.png", "out.PNG", "out.obj", "out.ply", "out.stl", "out.step", "out.csv", "out.json"})
    expect_usage_error(std::string("preprocess object.ply -o ") + output, output);
  expect_nothing_written(3);
}

TEST_F(HostileOptions, SeveralObjectsRefuseAnAccuracyTheirPairsWouldIgnore) {
  touch("model.tpi");
  touch("a.ply");
  touch("b.ply");
  touch("a.csv");
  touch("b.csv");
  const std::string group =
      "fly model.tpi --object a.ply --path a.csv --object b.ply --path b.csv ";
  expect_usage_error(group + "--accuracy clearance:2", "--accuracy clearance:2");
  expect_usage_error(group + "--accuracy double_eps", "--accuracy double_eps");
  expect_usage_error(group + "--query distance", "--query");
  expect_nothing_written(5);
}

TEST_F(HostileOptions, MisspeltCommandsAndOptionsNameTheNearestOne) {
  expect_usage_error("instpect model.tpi", "unknown command 'instpect'; did you mean 'inspect'?");
  expect_usage_error("generate scen -o x.ply", "unknown command 'scen'; did you mean 'scene'?");
  expect_usage_error("mesh conver a.ply -o b.ply", "did you mean 'convert'?");
  expect_usage_error("frobnicate", "unknown command 'frobnicate' (generate, ");
  touch("model.tpi");
  touch("x");
  expect_usage_error("fly model.tpi --obect x --path x",
                     "unknown option '--obect' of fly; did you mean '--object'?");
  expect_usage_error("render model.tpi -o v.png --zom 2", "did you mean '--zoom'?");
  expect_usage_error("preprocess x -o m.tpi --memroy 1G", "did you mean '--memory'?");
  expect_usage_error("--verison", "did you mean '--version'?");
  expect_nothing_written(2);
}

TEST_F(HostileOptions, TheHelpDescribesEveryCommand) {
  std::string help;
  ASSERT_EQ(test::run_cli("--help", help), 0);
  const std::size_t commands_section = help.find("Subcommands:");
  ASSERT_NE(commands_section, std::string::npos) << help;
  const std::string description = help.substr(0, help.find("Usage:"));
  std::istringstream listed(help.substr(commands_section));
  std::size_t commands = 0;
  for (std::string line; std::getline(listed, line);) {
    std::istringstream words(line);
    std::string name;
    // A command's line starts at the third column; its description goes on further right.
    if (line.size() > 2 && line.starts_with("  ") && line[2] != ' ' && (words >> name)) {
      ++commands;
      EXPECT_NE(description.find(name), std::string::npos) << name << " undescribed:\n"
                                                           << description;
    }
  }
  EXPECT_GE(commands, 9u);
}

TEST_F(HostileOptions, ASymbolicLinkLoopIsNamedAsOne) {
  fs::create_symlink("loop", folder_ / "loop");
  expect_usage_error("preprocess loop -o x.tpi", "loop of symbolic links");
  expect_usage_error("mesh info loop", "loop of symbolic links");
  expect_usage_error("mesh info missing.ply", "'missing.ply' does not exist");
  expect_nothing_written(1);
}

// The message `read` throws for `bytes` written to `name`.
template <typename Read>
std::string message_reading(const fs::path& path, const std::string& bytes, Read read) {
  std::ofstream(path, std::ios::binary) << bytes;
  try {
    read(path);
  } catch (const Error& error) {
    return error.what();
  }
  ADD_FAILURE() << path << " was read";
  return {};
}

// A message that quotes an input stays one short line of printable text.
void expect_printable_and_short(const std::string& message) {
  EXPECT_LT(message.size(), 300u) << message;
  for (const char c : message)
    EXPECT_TRUE(c >= 0x20 && c < 0x7f)
        << "byte " << int(static_cast<unsigned char>(c)) << " in " << message;
}

TEST_F(HostileOptions, QuotedInputIsCutAndEscaped) {
  const std::string binary = std::string("\x01\xff\x00tail\n", 7) + std::string(500, 'z');
  const std::string header = "tx,ty,tz,qw,qx,qy,qz\n";
  const std::string pose_message =
      message_reading(folder_ / "poses.csv", header + "0,0,0,1,0,0," + binary + "\n",
                      [](const fs::path& path) { read_poses(path); });
  expect_printable_and_short(pose_message);
  EXPECT_NE(pose_message.find("'\\x01\\xff\\x00tail"), std::string::npos) << pose_message;
  EXPECT_NE(pose_message.find("zzz...'"), std::string::npos) << pose_message;
  const std::string bad_header = message_reading(folder_ / "header.csv", binary + "\n",
                                                 [](const fs::path& path) { read_poses(path); });
  expect_printable_and_short(bad_header);
  const std::string answer_message =
      message_reading(folder_ / "answers.csv", "step,collides\n0," + binary + "\n",
                      [](const fs::path& path) { read_answers(path); });
  expect_printable_and_short(answer_message);
  EXPECT_NE(answer_message.find("\\x01\\xff\\x00tail"), std::string::npos) << answer_message;
}

std::string exactly(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

TEST_F(HostileOptions, PoseFilesTakeTheRuntimesRuleForUnitQuaternions) {
  const std::string header = "tx,ty,tz,qw,qx,qy,qz\n";
  const auto read = [](const fs::path& path) { read_poses(path); };
  // Length 2: once normalised silently, while the C API and Python refused it.
  const std::string twice =
      message_reading(folder_ / "twice.csv", header + "0,0,0,1,0,0,0\n0,0,0,2,0,0,0\n", read);
  EXPECT_NE(twice.find("line 3"), std::string::npos) << twice;
  EXPECT_NE(twice.find("length 2"), std::string::npos) << twice;
  // Just beyond and just within the tolerance of the squared length.
  const double beyond = std::sqrt(1 + 2 * kUnitQuaternionTolerance);
  const double within = std::sqrt(1 + 0.5 * kUnitQuaternionTolerance);
  const std::string off =
      message_reading(folder_ / "off.csv", header + "0,0,0," + exactly(beyond) + ",0,0,0\n", read);
  EXPECT_NE(off.find("line 2"), std::string::npos) << off;
  std::ofstream(folder_ / "near.csv") << header << "0,0,0," << exactly(within) << ",0,0,0\n";
  const std::vector<Pose> near = read_poses(folder_ / "near.csv");
  ASSERT_EQ(near.size(), 1u);
  EXPECT_TRUE(is_unit_quaternion(near[0].rotation));
  EXPECT_DOUBLE_EQ(near[0].rotation[0], 1.0);  // normalised
}

}  // namespace
}  // namespace tetrapage
