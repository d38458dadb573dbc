#pragma once
/// @file TemporaryFiles.h
/// Temporary files that must not outlive an interrupted run: each writer registers its
/// temporary while it exists; a command installs handlers so that SIGINT and SIGTERM remove
/// every registered file before the process ends as the signal asks. After a SIGKILL (no
/// handler runs) the next writer of the same output removes the temporaries of processes
/// that no longer exist.

#include <cstddef>
#include <filesystem>
#include <vector>

namespace tetrapage {

/// Keeps `path` registered while it lives (at most 64 at once; more are not registered, and
/// only the stale-temporary sweep then removes them).
class TemporaryFileGuard {
 public:
  explicit TemporaryFileGuard(const std::filesystem::path& path);
  ~TemporaryFileGuard();
  TemporaryFileGuard(const TemporaryFileGuard&) = delete;
  TemporaryFileGuard& operator=(const TemporaryFileGuard&) = delete;

 private:
  int slot_ = -1;
};

/// SIGINT and SIGTERM remove every registered temporary, then end the process as the signal's
/// default action would (exit status 128 + signal for a shell). Idempotent.
void remove_temporaries_on_signals();

/// Removes `OUTPUT.tmp-PID` files beside `output` whose process PID no longer exists (left by a
/// killed writer); returns what it removed.
std::vector<std::filesystem::path> remove_stale_temporaries(const std::filesystem::path& output);

}  // namespace tetrapage
