#pragma once
// Runs the `tetrapage` command line from a test: its exit status and its stdout.

#include <sys/wait.h>

#include <cstdio>
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

}  // namespace tetrapage::test
