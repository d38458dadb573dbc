#pragma once
/// @file Progress.h
/// Progress reporting for long work: a bar on a terminal, plain lines otherwise, on stderr.
/// Long operations take a Progress& and call advance(); Progress::silent() discards.

#include <chrono>
#include <cstdint>
#include <string>

namespace tetrapage {

class Progress {
 public:
  /// @param label what is being done ("reading parts", "writing scene").
  /// @param total units of work, 0 if unknown.
  Progress(std::string label, std::uint64_t total, bool enabled = true);
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

  std::string label_;
  std::uint64_t total_;
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
