#include "tetrapage/formats/FileChecks.h"

#include <sys/stat.h>

#include <cstring>
#include <string>

#include "tetrapage/formats/Error.h"

namespace tetrapage {
namespace {

std::string kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

// Whether two existing paths name the same file.
bool same_file(const struct stat& a, const struct stat& b) { return a.st_dev == b.st_dev && a.st_ino == b.st_ino; }

}  // namespace

void require_regular_file(const std::filesystem::path& path) {
  struct stat status {};
  if (::stat(path.c_str(), &status) != 0) return;  // opening it says why
  if (!S_ISREG(status.st_mode))
    throw IoError("cannot read '" + path.string() + "': it is " + kind_of(status.st_mode) + ", not a regular file");
}

void check_outputs(std::span<const std::filesystem::path> outputs, std::span<const std::filesystem::path> inputs) {
  for (const std::filesystem::path& output : outputs) {
    if (output.empty()) continue;
    struct stat status {};
    if (::stat(output.c_str(), &status) != 0) continue;  // a new file: nothing to destroy
    if (!S_ISREG(status.st_mode))
      throw InputError("refusing to write '" + output.string() + "': it is " + kind_of(status.st_mode) +
                       ", not a regular file");
    for (const auto& input : inputs) {
      struct stat other {};
      if (!input.empty() && ::stat(input.c_str(), &other) == 0 && same_file(status, other))
        throw InputError("refusing to write '" + output.string() + "': it is the input '" + input.string() + "'");
    }
  }
  // Two outputs naming one file, existing or not.
  for (std::size_t i = 0; i < outputs.size(); ++i)
    for (std::size_t j = 0; j < i; ++j) {
      if (outputs[i].empty() || outputs[j].empty()) continue;
      std::error_code ignored;
      if (std::filesystem::weakly_canonical(outputs[i], ignored) == std::filesystem::weakly_canonical(outputs[j], ignored))
        throw InputError("refusing to write '" + outputs[i].string() + "' twice (it is also '" + outputs[j].string() + "')");
    }
}

}  // namespace tetrapage
