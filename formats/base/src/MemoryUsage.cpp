#include "tetrapage/formats/base/MemoryUsage.h"

#include <fstream>
#include <string>

namespace tetrapage {
namespace {

// A "Key:   1234 kB" line of /proc/self/status, in bytes.
std::uint64_t status_field(const char* key) {
  std::ifstream status("/proc/self/status");
  std::string line;
  const std::string prefix = std::string(key) + ":";
  while (std::getline(status, line)) {
    if (line.compare(0, prefix.size(), prefix) != 0) continue;
    return std::stoull(line.substr(prefix.size())) * 1024;
  }
  return 0;
}

}  // namespace

std::uint64_t resident_bytes() { return status_field("VmRSS"); }

std::uint64_t peak_resident_bytes() { return status_field("VmHWM"); }

bool reset_peak_resident() {
  std::ofstream clear_refs("/proc/self/clear_refs");
  clear_refs << "5";
  clear_refs.flush();
  return bool(clear_refs);
}

}  // namespace tetrapage
