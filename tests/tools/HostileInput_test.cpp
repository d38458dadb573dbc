// The command line against hostile inputs and outputs: an output that is an input, a device, a
// FIFO or a folder; inputs that are FIFOs; bad option values; a run interrupted by a signal or
// killed; an index validated from another folder or moved with its model. Every refusal is one
// line on stderr, a non-zero exit (2 for a command-line mistake), and nothing written or left.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "HostileSupport.h"
#include "tetrapage/formats/mesh/Pose.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;

using CliRun = test::CliResult;
using test::expect_refused;
using test::leftovers;
using test::read_file;
using test::run;
using HostileInput = test::HostileFolder;

TEST_F(HostileInput, AnOutputThatIsAnInputIsRefusedAndTheInputKept) {
  const fs::path model = make_model("same.ply", 400);
  const std::string before = read_file(model);
  // An index is never written under a mesh's name: refused as a command-line mistake first.
  expect_refused(run(folder_, "preprocess same.ply -o same.ply"), "same.ply", 2);
  expect_refused(run(folder_, "preprocess same.ply -o ./same.ply"), "names a mesh", 2);
  expect_refused(run(folder_, "mesh convert same.ply -o same.ply"), "is the input");
  EXPECT_EQ(read_file(model), before);
  // A pose file given as the answers of the flight over it.
  ASSERT_EQ(run(folder_, "preprocess same.ply -o model.tpi").status, 0);
  ASSERT_EQ(run(folder_, "generate object --triangles 4 -o object.ply").status, 0);
  write_poses(folder_ / "flight.csv", std::vector<Pose>(3));
  const std::string poses = read_file(folder_ / "flight.csv");
  expect_refused(
      run(folder_, "fly model.tpi --object object.ply --path flight.csv --answers flight.csv"),
      "flight.csv");
  expect_refused(
      run(folder_,
          "fly model.tpi --object object.ply --path flight.csv --answers a.csv --report a.csv"),
      "twice");
  EXPECT_EQ(read_file(folder_ / "flight.csv"), poses);
  EXPECT_TRUE(leftovers(folder_).empty());
}

TEST_F(HostileInput, OutputsThatAreNotRegularFilesAreRefused) {
  make_model("model.ply", 400);
  ASSERT_EQ(::mkfifo((folder_ / "out.fifo").c_str(), 0600), 0);
  ASSERT_EQ(::mkfifo((folder_ / "fifo.ply").c_str(), 0600), 0);
  fs::create_directories(folder_ / "out.tpi");
  expect_refused(run(folder_, "preprocess model.ply -o out.fifo"), "FIFO");
  expect_refused(run(folder_, "preprocess model.ply -o out.tpi"), "folder");
  expect_refused(run(folder_, "mesh convert model.ply -o fifo.ply"), "FIFO");
  expect_refused(run(folder_, "generate object --triangles 4 -o fifo.ply"), "FIFO");
  struct stat status {};
  ASSERT_EQ(::stat((folder_ / "out.fifo").c_str(), &status), 0);
  EXPECT_TRUE(S_ISFIFO(status.st_mode)) << "the FIFO must survive";
  EXPECT_TRUE(fs::is_directory(folder_ / "out.tpi"));
  // A device node (read-only checks: the node itself is never written).
  expect_refused(run(folder_, "preprocess model.ply -o /dev/null"), "character device");
  EXPECT_TRUE(leftovers(folder_).empty());
}

TEST_F(HostileInput, FifosAsInputsFailAtOnce) {
  make_model("model.ply", 400);
  ASSERT_EQ(run(folder_, "preprocess model.ply -o model.tpi").status, 0);
  ASSERT_EQ(run(folder_, "generate object --triangles 4 -o object.ply").status, 0);
  write_poses(folder_ / "flight.csv", std::vector<Pose>(3));
  for (const char* name : {"in.ply", "in.tpi", "in.csv", "in.json"})
    ASSERT_EQ(::mkfifo((folder_ / name).c_str(), 0600), 0);
  const auto start = std::chrono::steady_clock::now();
  expect_refused(run(folder_, "mesh info in.ply"), "FIFO");
  expect_refused(run(folder_, "mesh info in.json"), "FIFO");
  expect_refused(run(folder_, "validate in.tpi"), "in.tpi");
  expect_refused(run(folder_, "inspect in.tpi"), "in.tpi");
  expect_refused(run(folder_, "fly in.tpi --object object.ply --path flight.csv"), "in.tpi");
  expect_refused(run(folder_, "fly model.tpi --object in.ply --path flight.csv"), "FIFO");
  expect_refused(run(folder_, "fly model.tpi --object object.ply --path in.csv"), "FIFO");
  expect_refused(run(folder_, "preprocess in.ply -o x.tpi"), "FIFO");
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(50))
      << "nothing may wait on a FIFO";
  EXPECT_FALSE(fs::exists(folder_ / "x.tpi"));
}

TEST_F(HostileInput, BadOptionValuesAreCommandLineMistakes) {
  make_model("model.ply", 400);
  expect_refused(run(folder_, "preprocess model.ply -o x.tpi --memory 12Q"), "12Q", 2);
  expect_refused(run(folder_, "preprocess model.ply -o x.tpi --memory -5M"), "-5M", 2);
  expect_refused(run(folder_, "preprocess model.ply -o x.tpi --region-triangles -1"), "from 0 to",
                 2);
  ASSERT_EQ(run(folder_, "preprocess model.ply -o model.tpi").status, 0);
  expect_refused(run(folder_, "render model.tpi -o view.png --size -5x3"), "-5x3", 2);
  expect_refused(run(folder_, "render model.tpi -o view.png --size 0x3"), "0x3", 2);
  EXPECT_FALSE(fs::exists(folder_ / "x.tpi"));
  EXPECT_FALSE(fs::exists(folder_ / "view.png"));
}

// Coordinates whose placement or box would overflow are named, not taken for "no tet reachable".
TEST_F(HostileInput, CoordinatesThatWouldOverflowAreNamed) {
  std::ofstream(folder_ / "huge.obj")
      << "v 0 0 0\nv 1e308 0 0\nv 0 1e308 0\nv 0 0 1e308\nf 1 2 3\nf 1 3 4\nf 1 2 4\nf 2 3 4\n";
  expect_refused(run(folder_, "preprocess huge.obj -o huge.tpi"), "1e+308");
  EXPECT_FALSE(fs::exists(folder_ / "huge.tpi"));
  make_model("model.ply", 400);
  ASSERT_EQ(run(folder_, "preprocess model.ply -o model.tpi").status, 0);
  ASSERT_EQ(run(folder_, "generate object --triangles 4 -o object.ply").status, 0);
  std::ofstream(folder_ / "far.csv") << "tx,ty,tz,qw,qx,qy,qz\n1e308,0,0,1,0,0,0\n";
  expect_refused(run(folder_, "fly model.tpi --object object.ply --path far.csv"), "1e+308");
  expect_refused(run(folder_, "fly model.tpi --object huge.obj --path far.csv"), "1e+308");
}

// SIGINT, SIGTERM, SIGHUP, SIGPIPE, SIGALRM and SIGUSR1 during a preprocess that spills remove
// its temporary index and spill files; a SIGKILL's leftovers are removed by the next preprocess of
// the same output.
TEST_F(HostileInput, InterruptedAndKilledRunsLeaveNothingBehind) {
  make_model("model.ply", 300'000);
  for (const int signal_number : {SIGINT, SIGTERM, SIGHUP, SIGPIPE, SIGALRM, SIGUSR1, SIGKILL}) {
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      ::chdir(folder_.c_str());
      ::freopen("/dev/null", "w", stderr);
      ::freopen("/dev/null", "w", stdout);
      ::execl(TETRAPAGE_CLI, TETRAPAGE_CLI, "preprocess", "model.ply", "-o", "out.tpi", "--memory",
              "16M", "--threads", "1", static_cast<char*>(nullptr));
      ::_exit(127);
    }
    // Wait for the temporary index to appear (the run is then writing), then interrupt.
    const fs::path temporary = folder_ / ("out.tpi.tmp-" + std::to_string(child));
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (!fs::exists(temporary) && std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    ASSERT_TRUE(fs::exists(temporary)) << "the preprocess must reach its writing stage";
    ::kill(child, signal_number);
    int status = 0;
    ::waitpid(child, &status, 0);
    ASSERT_TRUE(WIFSIGNALED(status)) << "signal " << signal_number;
    EXPECT_EQ(WTERMSIG(status), signal_number);
    EXPECT_FALSE(fs::exists(folder_ / "out.tpi"));
    const auto left = leftovers(folder_);
    if (signal_number == SIGKILL) {
      EXPECT_EQ(left, std::vector<std::string>{temporary.filename().string()})
          << "only the index's temporary";
      const CliRun again = run(folder_, "preprocess model.ply -o out.tpi --memory 16M");
      EXPECT_EQ(again.status, 0) << again.err;
      EXPECT_NE(again.out.find("removed 1 temporary"), std::string::npos) << again.out;
      EXPECT_TRUE(leftovers(folder_).empty());
    } else {
      EXPECT_TRUE(left.empty()) << "signal " << signal_number << ": "
                                << (left.empty() ? "" : left[0]);
    }
  }
}

// The index finds its model from any working directory, and after both moved together; a
// missing model is said, not taken for an empty one.
TEST_F(HostileInput, ValidateFindsTheModelRelativeToTheIndex) {
  fs::create_directories(folder_ / "a" / "index");
  make_model("a/model.ply", 2000);
  ASSERT_EQ(run(folder_ / "a", "preprocess model.ply -o index/model.tpi").status, 0);
  CliRun r = run(folder_, "validate a/index/model.tpi");
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("all equal"), std::string::npos) << r.out;
  fs::rename(folder_ / "a", folder_ / "b");
  r = run(fs::path("/"), "validate '" + (folder_ / "b" / "index" / "model.tpi").string() + "'");
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("all equal"), std::string::npos) << r.out;
  fs::remove(folder_ / "b" / "model.ply");
  r = run(folder_, "validate b/index/model.tpi");
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("not found"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace tetrapage
