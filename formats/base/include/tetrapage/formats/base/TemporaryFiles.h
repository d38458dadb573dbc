#pragma once
/// @file TemporaryFiles.h
/// Temporary files that must not outlive an interrupted run: each writer registers its
/// temporary while it exists; a command installs handlers so that SIGINT and SIGTERM remove
/// every registered file before the process ends as the signal asks. After a SIGKILL (no
/// handler runs) the next writer of the same output removes the temporaries of processes
/// that no longer exist. Every writer names its temporary temporary_path(output), so that
/// the sweep recognises any of them.

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

/// Every signal whose default action ends the process (SIGINT, SIGTERM, SIGHUP, SIGPIPE: a
/// reader of stdout that went away, SIGQUIT, SIGALRM, SIGUSR1, SIGUSR2, SIGXCPU, SIGXFSZ,
/// SIGVTALRM, SIGPROF) removes every registered temporary, then ends the process as the
/// signal's default action would (exit status 128 + signal for a shell). A signal the process
/// was started with ignored (nohup's SIGHUP) stays ignored. Idempotent.
void remove_temporaries_on_signals();

/// The temporary a writer of `output` fills before renaming it over `output`:
/// "OUTPUT.tmp-PID" beside it.
std::filesystem::path temporary_path(const std::filesystem::path& output);

/// Removes `OUTPUT.tmp-PID` files beside `output` whose process PID no longer exists (left by a
/// killed writer); returns what it removed.
std::vector<std::filesystem::path> remove_stale_temporaries(const std::filesystem::path& output);

}  // namespace tetrapage
