#pragma once
// Shared helpers of the formats tests: scratch folders, files written byte by byte, checks
// that an exception has the right type and names what it should, and random meshes.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/tools/Random.h"

namespace tetrapage::test {

/// A fresh, empty folder for one test. ctest runs test cases in parallel processes, so the
/// folder is under the running test's own name.
inline std::filesystem::path scratch_folder(const std::string& name) {
  const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string test_name = test != nullptr
                              ? std::string(test->test_suite_name()) + "." + test->name()
                              : std::string("no_test");
  std::replace(test_name.begin(), test_name.end(), '/', '_');
  const auto folder = std::filesystem::path(TETRAPAGE_TEST_TMP) / "formats" / test_name / name;
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  return folder;
}

/// The names in a folder, sorted.
inline std::vector<std::string> folder_listing(const std::filesystem::path& folder) {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(folder))
    names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

inline void write_file(const std::filesystem::path& path, std::string_view bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  ASSERT_TRUE(out.good()) << path;
}

inline std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// Appends the bytes of a scalar in the requested byte order.
class Bytes {
 public:
  explicit Bytes(bool big_endian = false) : big_endian_(big_endian) {}
  template <class T>
  Bytes& put(T value) {
    char raw[sizeof(T)];
    std::memcpy(raw, &value, sizeof(T));
    if (big_endian_ != (std::endian::native == std::endian::big))
      std::reverse(raw, raw + sizeof(T));
    data_.append(raw, sizeof(T));
    return *this;
  }
  Bytes& text(std::string_view text) {
    data_.append(text);
    return *this;
  }
  const std::string& str() const { return data_; }

 private:
  bool big_endian_;
  std::string data_;
};

/// Runs `action`, which must throw exactly E (not a sibling), whose message contains every
/// one of `parts`.
template <class E>
void expect_error(const std::function<void()>& action, const std::vector<std::string>& parts) {
  try {
    action();
    ADD_FAILURE() << "no exception thrown";
  } catch (const E& error) {
    const std::string message = error.what();
    for (const auto& part : parts) {
      EXPECT_NE(message.find(part), std::string::npos)
          << "message '" << message << "' does not contain '" << part << "'";
    }
  } catch (const Error& error) {
    ADD_FAILURE() << "wrong exception type: " << typeid(error).name() << ": " << error.what();
  }
}

/// The corners of every triangle, in order: what two soups must agree on whatever their
/// vertex numbering.
inline std::vector<std::array<Vec3, 3>> triangle_corners(const TriangleSoup& soup) {
  std::vector<std::array<Vec3, 3>> corners;
  for (std::size_t t = 0; t < soup.triangle_count(); ++t) corners.push_back(soup.corners(t));
  return corners;
}

/// What a read in chunks handed over, appended: each triangle's corners and part.
struct HandedOver {
  std::vector<std::array<Vec3, 3>> corners;
  std::vector<std::uint32_t> part_of;
  void add(const TriangleSoup& chunk) {
    for (std::size_t t = 0; t < chunk.triangle_count(); ++t) {
      corners.push_back(chunk.corners(t));
      part_of.push_back(chunk.part_of[t]);
    }
  }
};

/// A read in chunks (the parts it returned, `names`, and what it handed over) is `whole`.
inline void expect_whole_read(const TriangleSoup& names, const HandedOver& handed,
                              const TriangleSoup& whole) {
  EXPECT_EQ(names.triangle_count(), 0u);
  EXPECT_EQ(names.part_names, whole.part_names);
  EXPECT_EQ(names.part_paths, whole.part_paths);
  ASSERT_EQ(handed.corners.size(), whole.triangle_count());
  for (std::size_t t = 0; t < handed.corners.size(); ++t) {
    ASSERT_EQ(handed.corners[t], whole.corners(t)) << "triangle " << t;
    ASSERT_EQ(handed.part_of[t], whole.part_of[t]) << "triangle " << t;
  }
}

/// Rounds to the nearest float. Through a volatile on purpose: GCC 12.2 at -O2/-O3 vectorises
/// {double(float(a)), double(float(b)), ...} and drops the rounding of the vector lanes
/// (wrong code, seen on Debian's 12.2.0-14).
inline double round_to_float(double value) {
  volatile float narrowed = static_cast<float>(value);
  return narrowed;
}
inline Vec3 to_float(const Vec3& p) {
  return {round_to_float(p[0]), round_to_float(p[1]), round_to_float(p[2])};
}

/// A random soup of `parts` parts: vertices spread over magnitudes 1e-9 .. 1e9 (and signs),
/// non-degenerate triangles, a few unused vertices. Fixed by the seed.
inline TriangleSoup random_soup(std::uint64_t seed, int parts, int triangles_per_part) {
  Random random(seed);
  TriangleSoup soup;
  for (int part = 0; part < parts; ++part) {
    soup.part_names.push_back("part" + std::to_string(part));
    const auto base = static_cast<std::uint32_t>(soup.vertices.size());
    const int vertex_count = triangles_per_part / 2 + 4;
    for (int v = 0; v < vertex_count; ++v) {
      Vec3 p;
      for (double& c : p) {
        const double magnitude = std::pow(10.0, random.uniform(-9.0, 9.0));
        c = (random.uniform() < 0.5 ? -1 : 1) * magnitude * random.uniform(1.0, 10.0);
      }
      soup.vertices.push_back(p);
    }
    for (int t = 0; t < triangles_per_part;) {
      TriangleIndices tri;
      for (auto& index : tri) index = base + static_cast<std::uint32_t>(random.below(vertex_count));
      const auto c =
          std::array<Vec3, 3>{soup.vertices[tri[0]], soup.vertices[tri[1]], soup.vertices[tri[2]]};
      if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;
      // Also non-degenerate once rounded to float, so float formats keep every triangle.
      if (is_degenerate_triangle(c[0], c[1], c[2]) ||
          is_degenerate_triangle(to_float(c[0]), to_float(c[1]), to_float(c[2])))
        continue;
      soup.triangles.push_back(tri);
      soup.part_of.push_back(static_cast<std::uint32_t>(part));
      ++t;
    }
  }
  return soup;
}

}  // namespace tetrapage::test
