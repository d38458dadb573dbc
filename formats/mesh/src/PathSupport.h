#pragma once
// File-name helpers shared by the readers, the writer and the manifest loader.

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>

namespace tetrapage::detail {

/// The extension with its dot, in lower case (".PLY" -> ".ply"): formats go by extension.
inline std::string lower_extension(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

}  // namespace tetrapage::detail
