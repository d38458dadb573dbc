#pragma once
// What the tests of hostile command lines share: a fresh folder per test, the command run there
// under a timeout, the shape of a refusal, and the temporaries a run may not leave behind.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "RunCli.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/tools/TetrasGenerator.h"

namespace tetrapage::test {

inline std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// Under a 60 s timeout: a hang fails, it never blocks the suite.
inline CliResult run(const std::filesystem::path& folder, const std::string& arguments) {
  return run_cli_in(folder, arguments, 60);
}

/// One line on stderr naming `what`, exit `status` (2: a command-line mistake).
inline void expect_refused(const CliResult& r, const std::string& what, int status = 1) {
  EXPECT_EQ(r.status, status) << r.err;
  ASSERT_FALSE(r.err.empty());
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "one line: " << r.err;
  EXPECT_NE(r.err.find(what), std::string::npos) << r.err;
  EXPECT_LT(r.err.size(), 400u) << r.err;
}

/// Temporary files and spills in `folder` (a run must leave none).
inline std::vector<std::string> leftovers(const std::filesystem::path& folder) {
  std::vector<std::string> found;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    const std::string name = entry.path().filename().string();
    if (name.find(".tmp") != std::string::npos ||
        name.find(".tetrapage-spill") != std::string::npos)
      found.push_back(name);
  }
  return found;
}

/// A fresh folder per test, removed after it.
class HostileFolder : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_ = std::filesystem::path(TETRAPAGE_TEST_TMP) /
              ("hostile-" + std::to_string(::getpid()) + "-" +
               ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(folder_);
    std::filesystem::create_directories(folder_);
  }
  void TearDown() override {
    std::error_code ignored;
    std::filesystem::remove_all(folder_, ignored);
  }
  /// A model of `triangles` random tetrahedra's faces.
  std::filesystem::path make_model(const std::string& name, std::uint64_t triangles) const {
    const std::filesystem::path path = folder_ / name;
    TetrasOptions options;
    options.triangles = triangles;
    MeshWriter writer(path);
    generate_tetras(options, writer);
    writer.commit();
    return path;
  }
  std::filesystem::path folder_;
};

}  // namespace tetrapage::test
