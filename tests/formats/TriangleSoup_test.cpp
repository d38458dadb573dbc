// TriangleSoup's parts: names and instance paths stay one per part, whatever the order in which
// parts with and without paths are added or appended.

#include <gtest/gtest.h>

#include "tetrapage/formats/base/TriangleSoup.h"

namespace tetrapage {
namespace {

/// Every part's path, by part_path (the name when none is stored).
std::vector<std::string> paths_of(const TriangleSoup& soup) {
  std::vector<std::string> paths;
  for (std::size_t p = 0; p < soup.part_count(); ++p) paths.push_back(soup.part_path(p));
  return paths;
}

TEST(TriangleSoup, AddPartKeepsAPathPerPartFromTheFirstOneOn) {
  TriangleSoup plain;
  plain.add_part("a");
  plain.add_part("b");
  EXPECT_TRUE(plain.part_paths.empty());  // every path is its name: none stored
  EXPECT_EQ(paths_of(plain), (std::vector<std::string>{"a", "b"}));

  TriangleSoup first;  // the first part already has a path of its own
  first.add_part("U7", "board#0/U7");
  first.add_part("frame");
  EXPECT_EQ(first.part_names, (std::vector<std::string>{"U7", "frame"}));
  EXPECT_EQ(first.part_paths, (std::vector<std::string>{"board#0/U7", "frame"}));

  TriangleSoup later;
  later.add_part("frame");
  later.add_part("U7", "board#1/U7");
  EXPECT_EQ(later.part_paths, (std::vector<std::string>{"frame", "board#1/U7"}));
}

TEST(TriangleSoup, AppendKeepsThePathsOfBothSoups) {
  TriangleSoup with_paths;
  with_paths.add_part("U7", "board#0/U7");
  TriangleSoup plain;
  plain.add_part("frame");
  for (const auto& [front, back] :
       {std::pair{&with_paths, &plain}, std::pair{&plain, &with_paths}}) {
    TriangleSoup joined;  // empty: the first append copies everything
    joined.append(*front);
    joined.append(*back);
    std::vector<std::string> expected = paths_of(*front);
    expected.push_back(back->part_path(0));
    EXPECT_EQ(paths_of(joined), expected);
    EXPECT_EQ(joined.part_paths.size(), joined.part_count());
  }
}

}  // namespace
}  // namespace tetrapage
