// The options the commands share (tools/cli/OptionChecks.cpp): every --memory shows the one
// default, kDefaultMemoryBudget, and how sizes are written.
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "RunCli.h"
#include "tetrapage/formats/base/ByteSize.h"

namespace tetrapage {
namespace {

// Every --memory of every command (found in the help of each command group) shows the one
// default and how sizes are written.
TEST(MemoryOption, EveryCommandStatesTheOneDefaultAndTheSizeConvention) {
  const std::string expected = "--memory TEXT:SIZE=" + byte_size_text(kDefaultMemoryBudget);
  std::size_t options = 0;
  for (const char* group : {"", "generate ", "mesh "}) {
    std::string help;
    ASSERT_EQ(test::run_cli(std::string(group) + "--help-all", help), 0) << group;
    std::vector<std::string> lines;
    std::istringstream text(help);
    for (std::string line; std::getline(text, line);) lines.push_back(line);
    for (std::size_t i = 0; i < lines.size(); ++i) {
      if (lines[i].find("--memory TEXT") == std::string::npos) continue;
      ++options;
      EXPECT_NE(lines[i].find(expected), std::string::npos) << lines[i];
      // The option's text goes on over the lines indented to its description column.
      std::string option = lines[i];
      for (std::size_t j = i + 1; j < lines.size() && lines[j].find_first_not_of(' ') >= 20; ++j) {
        option.push_back(
            ' ');  // appended, not " " + ...: GCC 12 warns falsely (-Wrestrict) on that
        option.append(lines[j], lines[j].find_first_not_of(' '));
      }
      EXPECT_NE(option.find("k, M, G, T are KiB, MiB, GiB, TiB (powers of 1024"), std::string::npos)
          << option;
    }
  }
  // fly, preprocess, render, generate flight.
  EXPECT_GE(options, 4u);
}

}  // namespace
}  // namespace tetrapage
