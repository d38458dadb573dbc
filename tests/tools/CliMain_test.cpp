// The `tetrapage` command's own flags (tools/cli/main.cpp), run as a user runs them.

#include <gtest/gtest.h>

#include <regex>
#include <string>

#include "RunCli.h"
#include "tetrapage/formats/index/IndexHeader.h"
#include "tetrapage/version.h"

namespace tetrapage {
namespace {

TEST(CliMain, VersionNamesTheReleaseAndTheIndexFormat) {
  std::string out;
  EXPECT_EQ(test::run_cli("--version", out), 0);
  EXPECT_EQ(out, std::string("tetrapage ") + TETRAPAGE_VERSION_STRING + " (index format " +
                     std::to_string(kIndexVersion) + ")\n");
  EXPECT_TRUE(std::regex_match(
      out, std::regex("tetrapage [0-9]+\\.[0-9]+\\.[0-9]+ \\(index format [0-9]+\\)\n")))
      << out;
}

}  // namespace
}  // namespace tetrapage
