#pragma once
// A test helper shared by the test folders: runs an action in a forked child whose address
// space is capped (RLIMIT_AS), so that a reader that would allocate gigabytes for a few bytes
// of a hostile file fails the test instead of passing on an overcommitting machine.

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <functional>
#include <string>

#include "tetrapage/formats/base/Error.h"

namespace tetrapage::test {

/// How the action ended in the child: "returned", the exception's type ("FormatError",
/// "InputError", "IoError", "Error", "std::bad_alloc", "std::exception") or "crashed", and
/// the exception's message.
struct ChildOutcome {
  std::string kind;
  std::string message;
};

/// The process's mapped bytes now (VmSize), which the limit is added to.
inline std::size_t mapped_bytes() {
  std::ifstream statm("/proc/self/statm");
  std::size_t pages = 0;
  statm >> pages;
  return pages * static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
}

/// Runs `action` in a child process allowed `extra_bytes` of address space beyond what this
/// process maps now.
inline ChildOutcome run_with_memory_limit(const std::function<void()>& action,
                                          std::size_t extra_bytes = std::size_t(512) << 20) {
  int channel[2];
  if (::pipe(channel) != 0) return {"crashed", "pipe() failed"};
  std::fflush(nullptr);
  const pid_t child = ::fork();
  if (child == 0) {
    ::close(channel[0]);
    rlimit limit{};
    limit.rlim_cur = limit.rlim_max = mapped_bytes() + extra_bytes;
    ::setrlimit(RLIMIT_AS, &limit);
    std::string report;
    try {
      action();
      report = "returned\n";
    } catch (const FormatError& error) {
      report = std::string("FormatError\n") + error.what();
    } catch (const InputError& error) {
      report = std::string("InputError\n") + error.what();
    } catch (const IoError& error) {
      report = std::string("IoError\n") + error.what();
    } catch (const Error& error) {
      report = std::string("Error\n") + error.what();
    } catch (const std::bad_alloc& error) {
      report = std::string("std::bad_alloc\n") + error.what();
    } catch (const std::exception& error) {
      report = std::string("std::exception\n") + error.what();
    }
    for (std::size_t done = 0; done < report.size();) {
      const ssize_t wrote = ::write(channel[1], report.data() + done, report.size() - done);
      if (wrote <= 0) break;
      done += static_cast<std::size_t>(wrote);
    }
    ::_exit(0);  // no destructors, atexit handlers or gtest output in the child
  }
  ::close(channel[1]);
  std::string received;
  char buffer[4096];
  for (ssize_t got; (got = ::read(channel[0], buffer, sizeof buffer)) > 0;) received.append(buffer, std::size_t(got));
  ::close(channel[0]);
  int status = 0;
  ::waitpid(child, &status, 0);
  const auto newline = received.find('\n');
  if (!WIFEXITED(status) || newline == std::string::npos)
    return {"crashed", "status " + std::to_string(status)};
  return {received.substr(0, newline), received.substr(newline + 1)};
}

}  // namespace tetrapage::test
