#pragma once
/// @file AnswerFile.h
/// Per-pose collision answers: CSV with the header `step,collides`, one row per pose (0/1).

#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

namespace tetrapage {

/// Writes answers under a temporary name renamed on success. @throw IoError.
void write_answers(const std::filesystem::path& path, std::span<const std::uint8_t> collides);

/// Reads answers. @throw IoError if unreadable; FormatError for a wrong header, a step out of
/// sequence or a value other than 0/1 (names file, line and value).
std::vector<std::uint8_t> read_answers(const std::filesystem::path& path);

}  // namespace tetrapage
