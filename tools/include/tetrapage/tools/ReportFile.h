#pragma once
/// @file ReportFile.h
/// The JSON reports every command writes with `--report`, and the early check that an output
/// can be written at all (before long work).

#include <filesystem>

#include <nlohmann/json.hpp>

namespace tetrapage {

/// Writes a JSON report under a temporary name and renames it (never half-written).
/// @throw IoError on failure.
void write_report(const std::filesystem::path& path, const nlohmann::json& report);

/// Fails early, before long work, when an output could not be written: creates and
/// removes `path`.tmp. Empty paths (optional outputs not asked for) are skipped.
/// @throw IoError naming the path and the reason.
void check_writable(const std::filesystem::path& path);

}  // namespace tetrapage
