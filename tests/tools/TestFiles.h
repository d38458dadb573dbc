#pragma once
// Files of the tools' tests: a fresh folder per test, a file's bytes (determinism checks).

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace tetrapage::test {

/// TETRAPAGE_TEST_TMP/group/name, emptied.
inline std::filesystem::path fresh_folder(const std::string& group, const std::string& name) {
  const auto folder = std::filesystem::path(TETRAPAGE_TEST_TMP) / group / name;
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  return folder;
}

inline std::string file_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace tetrapage::test
