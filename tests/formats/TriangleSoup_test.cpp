// Parts and their instance paths through add_part and append, whatever the order in which
// parts with and without paths arrive.

#include <gtest/gtest.h>

#include "tetrapage/formats/TriangleSoup.h"

namespace tetrapage {
namespace {

TEST(TriangleSoupParts, EveryPartKeepsItsPathWhateverTheOrder) {
  TriangleSoup soup;
  EXPECT_EQ(soup.add_part("screw", "rack/screw#0"), 0u);
  EXPECT_EQ(soup.add_part("plate"), 1u);
  EXPECT_EQ(soup.add_part("screw", "rack/screw#1"), 2u);
  ASSERT_EQ(soup.part_count(), 3u);
  EXPECT_EQ(soup.part_path(0), "rack/screw#0");
  EXPECT_EQ(soup.part_path(1), "plate");
  EXPECT_EQ(soup.part_path(2), "rack/screw#1");

  TriangleSoup plain;
  plain.add_part("a");
  plain.add_part("b");
  EXPECT_TRUE(plain.part_paths.empty());
  EXPECT_EQ(plain.part_path(1), "b");
  plain.append(soup);
  ASSERT_EQ(plain.part_count(), 5u);
  const std::vector<std::string> expected{"a", "b", "rack/screw#0", "plate", "rack/screw#1"};
  for (std::uint32_t p = 0; p < plain.part_count(); ++p) EXPECT_EQ(plain.part_path(p), expected[p]);
  EXPECT_EQ(plain.part_names[2], "screw");

  TriangleSoup later;
  later.append(plain);
  later.add_part("c");
  EXPECT_EQ(later.part_path(5), "c");
  EXPECT_EQ(later.part_path(2), "rack/screw#0");
}

}  // namespace
}  // namespace tetrapage
