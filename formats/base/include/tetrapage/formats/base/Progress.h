#pragma once
/// @file Progress.h
/// Progress reporting for long work: a bar on a terminal, plain lines otherwise, on stderr.
/// Long operations take a Progress& and call advance(); Progress::silent() discards.

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>

namespace tetrapage {

/// Told of progress as it is drawn (at most 10 times a second, and once at the end): the label,
/// the units done and the total (0 if unknown). Called from whichever thread advances the
/// Progress; an exception it throws stops the work that advanced it.
using ProgressCallback =
    std::function<void(std::string_view label, std::uint64_t done, std::uint64_t total)>;

class Progress {
 public:
  /// @param label what is being done ("reading parts", "writing scene").
  /// @param total units of work, 0 if unknown.
  /// @param enabled draw on stderr.
  /// @param callback also (or instead) tell this callback, if set.
  Progress(std::string label, std::uint64_t total, bool enabled = true,
           ProgressCallback callback = {});
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void advance(std::uint64_t units = 1);
  void set(std::uint64_t done);
  /// Prints the final state (100% or the count reached) once.
  void finish();

  std::uint64_t done() const { return done_; }
  double elapsed_seconds() const;

  /// A Progress that prints nothing (for tests and library calls with no terminal).
  static Progress& silent();

 private:
  void draw(bool final_line);

  void notify(bool final_call);

  std::string label_;
  std::uint64_t total_;
  ProgressCallback callback_;
  std::chrono::steady_clock::time_point last_notified_;
  std::uint64_t done_ = 0;
  bool enabled_;
  bool terminal_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
  int last_percent_ = -1;
  std::uint64_t last_drawn_done_ = ~std::uint64_t{0};
};

}  // namespace tetrapage
