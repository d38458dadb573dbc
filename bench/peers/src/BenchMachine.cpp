#include "tetrapage/bench/BenchMachine.h"

#include <sys/utsname.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

namespace tetrapage::bench {
namespace {

// The first line of `path` starting with `key`, its value after the colon (trimmed).
std::string proc_field(const char* path, const std::string& key) {
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(key, 0) != 0) continue;
    const auto colon = line.find(':');
    if (colon == std::string::npos) return {};
    const auto first = line.find_first_not_of(" \t", colon + 1);
    return first == std::string::npos ? std::string() : line.substr(first);
  }
  return {};
}

// The first line a command prints (empty when it cannot run).
std::string first_line_of(const char* command) {
  std::FILE* pipe = ::popen(command, "r");
  if (pipe == nullptr) return {};
  char buffer[512] = {};
  const bool read = std::fgets(buffer, sizeof buffer, pipe) != nullptr;
  ::pclose(pipe);
  std::string line = read ? buffer : "";
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.pop_back();
  return line;
}

// `flags` without -ffile-prefix-map=..., which names the folder the command ran in.
std::string without_path_maps(const std::string& flags) {
  std::istringstream words(flags);
  std::string word, kept;
  while (words >> word)
    if (word.rfind("-ffile-prefix-map=", 0) != 0) kept += (kept.empty() ? "" : " ") + word;
  return kept;
}

// A shared library as the distribution built it: its package's version and the flags its
// builds use by default (Debian's dpkg-buildflags: no -march, so the generic x86-64 baseline).
nlohmann::json distribution_library(const char* name, const char* package, const char* version) {
  const std::string query = std::string("dpkg-query -W -f='${Version}' ") + package + " 2>/dev/null";
  return {{"code", name},
          {"version", version},
          {"package", std::string(package) + " " + first_line_of(query.c_str())},
          {"flags", without_path_maps(first_line_of("dpkg-buildflags --get CXXFLAGS 2>/dev/null"))},
          {"built_by", "the distribution (Debian's default C++ flags, dpkg-buildflags)"}};
}

}  // namespace

std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string one, five, fifteen;
  in >> one >> five >> fifteen;
  return one + " " + five + " " + fifteen;
}

nlohmann::json machine_description() {
  utsname system{};
  ::uname(&system);
  char memory[32];
  std::snprintf(memory, sizeof memory, "%.1f GiB",
                std::strtod(proc_field("/proc/meminfo", "MemTotal").c_str(), nullptr) / double(1 << 20));
  return {{"processor", proc_field("/proc/cpuinfo", "model name")},
          {"logical_cores", ::sysconf(_SC_NPROCESSORS_ONLN)},
          {"memory", memory},
          {"kernel", std::string(system.sysname) + " " + system.release},
          {"load_average", load_average()}};
}

nlohmann::json build_description() {
  const nlohmann::json own = {{"compiler", TETRAPAGE_BENCH_COMPILER},
                              {"build_type", TETRAPAGE_BENCH_BUILD_TYPE},
                              {"flags", TETRAPAGE_BENCH_CXX_FLAGS},
                              {"built_by", "this build"}};
  nlohmann::json builds = nlohmann::json::array();
  for (const char* code : {"tetrapage", "CGAL (header-only)", "the harness"}) {
    nlohmann::json entry = own;
    entry["code"] = code;
    builds.push_back(entry);
  }
  builds.push_back(distribution_library("FCL", "libfcl0.7", TETRAPAGE_BENCH_FCL_VERSION));
  builds.push_back(distribution_library("Embree", "libembree3-3", TETRAPAGE_BENCH_EMBREE_VERSION));
  return builds;
}

}  // namespace tetrapage::bench
