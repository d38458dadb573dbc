#pragma once
/// @file ReportFile.h
/// The JSON reports every command writes with `--report`, and the early check that an output
/// can be written at all (before long work).

#include <filesystem>
#include <initializer_list>
#include <span>

#include <nlohmann/json.hpp>

namespace tetrapage {

/// Writes a JSON report under a temporary name and renames it (never half-written).
/// @throw IoError on failure.
void write_report(const std::filesystem::path& path, const nlohmann::json& report);

/// Fails early, before long work, when an output could not be written: creates and
/// removes `path`.tmp. Empty paths (optional outputs not asked for) are skipped.
/// @throw IoError naming the path and the reason.
void check_writable(const std::filesystem::path& path);

/// Every output checked before any work: none is an input, a non-regular file (a device node,
/// FIFO or folder) or another output (FileChecks.h), and each can be written (check_writable).
/// @throw InputError or IoError naming the output.
void check_outputs_writable(std::span<const std::filesystem::path> outputs,
                            std::span<const std::filesystem::path> inputs);
inline void check_outputs_writable(std::initializer_list<std::filesystem::path> outputs,
                                   std::initializer_list<std::filesystem::path> inputs) {
  check_outputs_writable(std::span<const std::filesystem::path>(outputs.begin(), outputs.size()),
                         std::span<const std::filesystem::path>(inputs.begin(), inputs.size()));
}

}  // namespace tetrapage
