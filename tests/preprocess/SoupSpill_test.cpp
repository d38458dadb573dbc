// SoupSpill: the ingested soups read back as records, the same in memory and spilled (also when
// the spill starts midway), ids and parts offset as asked, blocks of any size, gathers of any
// ids in memory; a damaged or truncated spill file is a clear error; nothing is left on disk.

#include "tetrapage/preprocess/SoupSpill.h"

#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>
#include <unistd.h>

#include <filesystem>

namespace tetrapage {
namespace {

namespace fs = std::filesystem;

struct Record {
  std::array<Vec3, 3> triangle;
  std::uint64_t id;
  std::uint32_t part;
  std::uint32_t tet;
};

TriangleSoup soup(std::size_t triangles, std::size_t parts, double shift) {
  TriangleSoup s;
  for (std::size_t v = 0; v < triangles + 2; ++v) s.vertices.push_back({shift + double(v), double(v * v), -double(v)});
  for (std::size_t t = 0; t < triangles; ++t) {
    s.triangles.push_back({std::uint32_t(t), std::uint32_t(t + 1), std::uint32_t(t + 2)});
    if (parts > 1) s.part_of.push_back(std::uint32_t(t % parts));
  }
  for (std::size_t p = 0; p < parts; ++p) s.part_names.push_back(std::to_string(p));
  return s;
}

std::vector<Record> read_back(SoupSpill<Record>& spill, std::size_t block) {
  std::vector<Record> all;
  spill.for_each_block(block, [&](std::span<const Record> records) {
    EXPECT_LE(records.size(), block);
    all.insert(all.end(), records.begin(), records.end());
  });
  return all;
}

TEST(SoupSpill, RecordsAreTheSameInMemoryAndSpilledMidway) {
  const fs::path folder = fs::path(TETRAPAGE_TEST_TMP) / ("soup-spill-" + std::to_string(::getpid()));
  fs::create_directories(folder);
  const std::vector<TriangleSoup> soups{soup(10, 1, 0), soup(25, 3, 100), soup(1, 1, 200), soup(40, 2, 300)};
  const std::vector<std::uint32_t> offsets{0, 1, 4, 5};
  // The expected records, from the soups themselves.
  std::vector<Record> expected;
  for (std::size_t s = 0; s < soups.size(); ++s)
    for (std::size_t t = 0; t < soups[s].triangle_count(); ++t)
      expected.push_back({soups[s].corners(t), std::uint64_t(expected.size()),
                          offsets[s] + (soups[s].part_of.empty() ? 0 : soups[s].part_of[t]), 0});
  for (const std::size_t spill_after : {std::size_t(0), std::size_t(2), soups.size()}) {
    SoupSpill<Record> spill;
    for (std::size_t s = 0; s < soups.size(); ++s) {
      if (s == spill_after) spill.spill_to(folder / "spill");
      spill.append(soups[s], offsets[s]);
    }
    EXPECT_EQ(spill.size(), expected.size());
    EXPECT_EQ(spill.spilled(), spill_after < soups.size());
    EXPECT_EQ(spill.held_bytes() > 0, spill_after > 0 && spill_after == soups.size());
    for (const std::size_t block : {std::size_t(1), std::size_t(7), std::size_t(1000)}) {
      const std::vector<Record> got = read_back(spill, block);
      ASSERT_EQ(got.size(), expected.size());
      for (std::size_t i = 0; i < got.size(); ++i) {
        EXPECT_EQ(got[i].triangle, expected[i].triangle) << i;
        EXPECT_EQ(got[i].id, expected[i].id) << i;
        EXPECT_EQ(got[i].part, expected[i].part) << i;
        EXPECT_EQ(got[i].tet, 0u) << i;
      }
    }
    if (!spill.spilled()) {
      // Gathers of ascending ids, within a soup and across soups, every id and none.
      std::vector<std::vector<std::uint64_t>> id_sets{{}, {0}, {3, 4, 5}, {9, 10, 34, 35, 36, 75}};
      id_sets.emplace_back();
      for (std::uint64_t id = 0; id < expected.size(); ++id) id_sets.back().push_back(id);
      for (const auto& ids : id_sets) {
        std::vector<std::array<Vec3, 3>> triangles{expected[1].triangle};  // appended to
        std::vector<std::uint32_t> parts{77};
        spill.gather(std::span<const std::uint64_t>(ids), triangles, parts);
        ASSERT_EQ(triangles.size(), ids.size() + 1);
        ASSERT_EQ(parts.size(), ids.size() + 1);
        for (std::size_t i = 0; i < ids.size(); ++i) {
          EXPECT_EQ(triangles[i + 1], expected[ids[i]].triangle) << ids[i];
          EXPECT_EQ(parts[i + 1], expected[ids[i]].part) << ids[i];
        }
      }
    }
    // Appending after a read goes on at the end.
    spill.append(soup(3, 1, 400), 9);
    EXPECT_EQ(read_back(spill, 64).back().id, expected.size() + 2);
    spill.clear();
    EXPECT_EQ(spill.size(), 0u);
    EXPECT_FALSE(fs::exists(folder / "spill"));
  }
  fs::remove_all(folder);
}

// The descriptor of this process that holds the (deleted) file `path`, or -1.
int open_descriptor_of(const fs::path& path) {
  for (const auto& entry : fs::directory_iterator("/proc/self/fd")) {
    std::error_code error;
    const std::string target = fs::read_symlink(entry.path(), error).string();
    if (!error && target.rfind(path.string(), 0) == 0) return std::stoi(entry.path().filename().string());
  }
  return -1;
}

TEST(SoupSpill, ATruncatedOrDamagedFileIsAnIoError) {
  const fs::path folder = fs::path(TETRAPAGE_TEST_TMP) / ("soup-spill-bad-" + std::to_string(::getpid()));
  fs::create_directories(folder);
  {
    SoupSpill<Record> spill;
    spill.spill_to(folder / "spill");
    spill.append(soup(50, 1, 0), 0);
    read_back(spill, 16);  // flushes
    // The spill file is unlinked once open: truncate it through the descriptor that holds it.
    const int descriptor = open_descriptor_of(folder / "spill");
    ASSERT_GE(descriptor, 0);
    struct stat status {};
    ASSERT_EQ(::fstat(descriptor, &status), 0);
    ASSERT_EQ(::ftruncate(descriptor, status.st_size - 10), 0);
    EXPECT_FALSE(fs::exists(folder / "spill")) << "unlinked while open";
    EXPECT_THROW(read_back(spill, 16), IoError);
  }
  EXPECT_FALSE(fs::exists(folder / "spill"));
  {
    SoupSpill<Record> spill;
    spill.spill_to(folder / "spill");
    TriangleSoup bad = soup(5, 1, 0);
    bad.triangles[2][1] = 1000;  // a corner beyond the vertices
    spill.append(bad, 0);
    EXPECT_THROW(read_back(spill, 16), IoError);
  }
  EXPECT_THROW(SoupSpill<Record>().spill_to(folder / "no-such-folder" / "spill"), IoError);
  fs::remove_all(folder);
}

}  // namespace
}  // namespace tetrapage
