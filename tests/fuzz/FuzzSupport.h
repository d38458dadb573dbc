#pragma once
// Shared by the libFuzzer targets: the readers under test take a path, so each target writes
// its input to one temporary file of its own (mkstemps, removed when the process exits) and
// rewrites it in place for every input.

#include <fcntl.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace tetrapage::fuzz {

class TempFile {
 public:
  /// A fresh file under $TMPDIR (else /tmp) ending in `suffix` (readers choose by extension).
  explicit TempFile(const std::string& suffix) {
    const char* folder = std::getenv("TMPDIR");
    std::string name = std::string(folder != nullptr && *folder != '\0' ? folder : "/tmp") +
                       "/tetrapage-fuzz-XXXXXX" + suffix;
    descriptor_ = ::mkstemps(name.data(), static_cast<int>(suffix.size()));
    if (descriptor_ < 0) std::abort();  // no input can be tried without it
    path_ = name;
  }
  ~TempFile() {
    ::close(descriptor_);
    ::unlink(path_.c_str());
  }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;

  /// Replaces the file's contents with `size` bytes.
  void write(const std::uint8_t* data, std::size_t size) {
    if (::ftruncate(descriptor_, 0) != 0) std::abort();
    std::size_t done = 0;
    while (done < size) {
      const ssize_t wrote = ::pwrite(descriptor_, data + done, size - done, static_cast<off_t>(done));
      if (wrote <= 0) std::abort();
      done += static_cast<std::size_t>(wrote);
    }
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  int descriptor_ = -1;
  std::filesystem::path path_;
};

}  // namespace tetrapage::fuzz
