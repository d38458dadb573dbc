#include "tetrapage/formats/base/SpinThenBlock.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <thread>
#include <vector>

namespace tetrapage {
namespace {

using namespace std::chrono_literals;

TEST(SpinThenBlock, SpinUntilStopsWhenDoneOrAfterItsLimit) {
  int polls = 0;
  EXPECT_TRUE(spin_until([&] { return ++polls == 50; }, 1s));
  EXPECT_EQ(polls, 50);
  const auto start = std::chrono::steady_clock::now();
  EXPECT_FALSE(spin_until([] { return false; }, 2ms));
  EXPECT_GE(std::chrono::steady_clock::now() - start, 2ms);
  polls = 0;
  EXPECT_FALSE(spin_until([&] { return ++polls < 0; }, 0us));
  EXPECT_EQ(polls, 1);  // no limit: asked once
}

// Threads that hold the lock for a moment each: every increment is seen (the lock excludes),
// whether the waiters poll past their limit and block (0 and 1 us) or get it while polling.
TEST(SpinThenBlock, LockSpinningFirstExcludes) {
  for (const auto limit : {0us, 1us, 200us}) {
    std::mutex mutex;
    long counter = 0;
    std::atomic<int> inside{0};
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t)
      threads.emplace_back([&] {
        for (int i = 0; i < 2000; ++i) {
          std::unique_lock lock = lock_spinning_first(mutex, limit);
          ASSERT_TRUE(lock.owns_lock());
          EXPECT_EQ(inside.fetch_add(1), 0);
          ++counter;
          if (i % 100 == 0) std::this_thread::sleep_for(10us);  // make the others block too
          inside.fetch_sub(1);
          lock.unlock();
          lock_spinning_first(lock, limit);  // and again through the relocking form
          ++counter;
        }
      });
    for (auto& thread : threads) thread.join();
    EXPECT_EQ(counter, 4 * 2000 * 2) << limit.count() << " us";
  }
}

}  // namespace
}  // namespace tetrapage
