#pragma once
/// @file AnswerCheck.h
/// Compares a run's per-pose answers with an answer file (`--check`), as `replay` and `fly` do.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace tetrapage {

class AnswerCheck {
 public:
  /// No check when `answers` is empty. `who` names the run in messages ("fly", "reference").
  /// @throw as read_answers; InputError when the file's row count differs from `poses`.
  AnswerCheck(const std::filesystem::path& answers, std::size_t poses, std::string who);

  /// Counts a disagreement at `step` (the first ten are printed on stderr).
  void record(std::size_t step, bool answer);
  /// Whether there are answers to compare with (a report states disagreements only then).
  bool checking() const { return !path_.empty(); }
  std::uint64_t disagreements() const { return disagreements_; }

  /// Prints the count on stdout (when checking).
  /// @throw Error when any answer disagreed.
  void finish() const;

 private:
  std::filesystem::path path_;
  std::string who_;
  std::vector<std::uint8_t> expected_;
  std::uint64_t disagreements_ = 0;
};

}  // namespace tetrapage
