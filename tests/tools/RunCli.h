#pragma once
// Runs the `tetrapage` command line from a test: its exit status, its stdout and its stderr.

#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace tetrapage::test {

/// Runs `tetrapage ARGUMENTS` (stderr discarded); returns the exit status (-1 when it did not
/// exit normally) and puts stdout in `out`.
inline int run_cli(const std::string& arguments, std::string& out) {
  const std::string command = std::string(TETRAPAGE_CLI) + " " + arguments + " 2>/dev/null";
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return -1;
  char buffer[4096];
  out.clear();
  while (std::size_t n = fread(buffer, 1, sizeof buffer, pipe)) out.append(buffer, n);
  const int status = pclose(pipe);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

struct CliResult {
  int status = -1;  ///< exit status; -1 when it did not exit normally
  std::string out, err;
};

/// Runs `tetrapage ARGUMENTS` in `folder` (relative paths are read there); stderr goes through
/// `folder`/stderr.txt, removed afterwards. With a timeout, a run still going after that many
/// seconds is ended (status 124: a hang fails a test, it never blocks the suite).
inline CliResult run_cli_in(const std::filesystem::path& folder, const std::string& arguments,
                            int timeout_seconds = 0) {
  const std::filesystem::path err = folder / "stderr.txt";
  const std::string limit =
      timeout_seconds > 0 ? "timeout " + std::to_string(timeout_seconds) + " " : "";
  const std::string command = "cd '" + folder.string() + "' && " + limit +
                              std::string(TETRAPAGE_CLI) + " " + arguments + " 2>'" + err.string() +
                              "'";
  CliResult result;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return result;
  char buffer[4096];
  while (std::size_t n = fread(buffer, 1, sizeof buffer, pipe)) result.out.append(buffer, n);
  const int status = pclose(pipe);
  result.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  {
    std::ifstream in(err, std::ios::binary);
    result.err.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  std::filesystem::remove(err);
  return result;
}

}  // namespace tetrapage::test
