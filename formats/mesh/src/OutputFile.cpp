#include "tetrapage/formats/mesh/OutputFile.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <vector>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/FileChecks.h"

namespace tetrapage {

namespace {

// The checks before the temporary exists: its rename must not replace anything but a file.
std::filesystem::path checked_temporary(const std::filesystem::path& output) {
  check_outputs(std::span<const std::filesystem::path>(&output, 1), {});
  remove_stale_temporaries(output);
  return temporary_path(output);
}

}  // namespace

OutputFile::OutputFile(std::filesystem::path output)
    : OutputFile(checked_temporary(output), output) {}

OutputFile::OutputFile(std::filesystem::path path, std::filesystem::path output)
    : path_(std::move(path)), output_(std::move(output)), guard_(path_) {
  // The temporary is renamed over the output at the end: never over a device, FIFO or folder.
  check_outputs(std::span<const std::filesystem::path>(&output_, 1), {});
  descriptor_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC | O_NOFOLLOW, 0666);
  if (descriptor_ < 0) fail("create", errno);
  buffer_ = std::make_unique_for_overwrite<char[]>(capacity_);
}

OutputFile::~OutputFile() {
  if (descriptor_ >= 0) ::close(descriptor_);
  if (!renamed_) ::unlink(path_.c_str());
}

void OutputFile::fail(const std::string& action, int error) const {
  std::string message = "cannot " + action + " '" + output_.string() + "'";
  if (path_ != output_) message += " (temporary file '" + path_.string() + "')";
  throw IoError(message + ": " + std::strerror(error));
}

void OutputFile::write_direct(const void* data, std::size_t size) {
  const char* bytes = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t done = ::write(descriptor_, bytes, size);
    if (done < 0) {
      if (errno == EINTR) continue;
      fail("write", errno);
    }
    bytes += done;
    size -= static_cast<std::size_t>(done);
    written_ += static_cast<std::uint64_t>(done);
  }
}

void OutputFile::flush() {
  if (used_ == 0) return;
  const std::size_t size = used_;
  used_ = 0;
  write_direct(buffer_.get(), size);
}

void OutputFile::write_at(std::uint64_t offset, const void* data, std::size_t size) {
  flush();
  const char* bytes = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t done = ::pwrite(descriptor_, bytes, size, static_cast<off_t>(offset));
    if (done < 0) {
      if (errno == EINTR) continue;
      fail("write", errno);
    }
    bytes += done;
    offset += static_cast<std::uint64_t>(done);
    size -= static_cast<std::size_t>(done);
  }
}

void OutputFile::append_file(OutputFile& other) {
  other.flush();
  flush();
  std::vector<char> block(1u << 20);
  std::uint64_t offset = 0;
  while (offset < other.written_) {
    const ssize_t got =
        ::pread(other.descriptor_, block.data(), block.size(), static_cast<off_t>(offset));
    if (got < 0) {
      if (errno == EINTR) continue;
      other.fail("read back", errno);
    }
    if (got == 0) other.fail("read back", EIO);
    write_direct(block.data(), static_cast<std::size_t>(got));
    offset += static_cast<std::uint64_t>(got);
  }
}

void OutputFile::rename_to(const std::filesystem::path& final_path) {
  flush();
  const int descriptor = descriptor_;
  descriptor_ = -1;
  if (::close(descriptor) != 0) fail("close", errno);
  if (::rename(path_.c_str(), final_path.c_str()) != 0) fail("rename to", errno);
  renamed_ = true;
}

}  // namespace tetrapage
