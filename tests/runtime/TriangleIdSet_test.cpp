// The step's set of met triangle ids against std::unordered_set, across growth and clears.

#include "tetrapage/runtime/query/TriangleIdSet.h"

#include <gtest/gtest.h>

#include <random>
#include <unordered_set>

namespace tetrapage {
namespace {

TEST(TriangleIdSet, AgreesWithAnUnorderedSetAcrossGrowthAndClears) {
  std::mt19937_64 random(7);
  TriangleIdSet set;
  for (int step = 0; step < 300; ++step) {
    set.clear();
    std::unordered_set<std::uint64_t> oracle;
    // Steps of a few ids to a few thousand (growth mid-step), drawn from a small range so that
    // repeats are common, and near 2^64 so that no bit is special.
    const std::size_t inserts = std::size_t(1) << (step % 13);
    const std::uint64_t base = step % 2 == 0 ? 0 : ~std::uint64_t{0} - 4 * inserts;
    std::uniform_int_distribution<std::uint64_t> id(0, 2 * inserts);
    for (std::size_t k = 0; k < inserts; ++k) {
      const std::uint64_t value = base + id(random);
      ASSERT_EQ(set.insert(value), oracle.insert(value).second)
          << "step " << step << " id " << value;
    }
    ASSERT_EQ(set.size(), oracle.size()) << "step " << step;
  }
}

TEST(TriangleIdSet, AClearForgetsEveryId) {
  TriangleIdSet set;
  for (std::uint64_t id = 0; id < 1000; ++id) EXPECT_TRUE(set.insert(id));
  set.clear();
  EXPECT_EQ(set.size(), 0u);
  for (std::uint64_t id = 0; id < 1000; ++id) EXPECT_TRUE(set.insert(id)) << id;
  for (std::uint64_t id = 0; id < 1000; ++id) EXPECT_FALSE(set.insert(id)) << id;
}

}  // namespace
}  // namespace tetrapage
