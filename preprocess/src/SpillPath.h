#pragma once
/// @file SpillPath.h
/// Where the preprocess's spill files go: beside the output (or in --spill-folder), named
/// after the process so that concurrent runs never share one.

#include <unistd.h>

#include <filesystem>
#include <string>

namespace tetrapage {

inline std::filesystem::path spill_path(const std::filesystem::path& folder,
                                        const std::string& what) {
  return folder / (".tetrapage-spill-" + std::to_string(::getpid()) + "-" + what);
}

}  // namespace tetrapage
