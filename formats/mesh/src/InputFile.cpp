#include "InputFile.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/FileChecks.h"

namespace tetrapage::detail {

InputFile::InputFile(const std::filesystem::path& path, std::size_t block_size)
    : path_(path), capacity_(std::max<std::size_t>(block_size, 4096)) {
  // Non-blocking: opening a FIFO would otherwise wait for a writer forever.
  descriptor_ = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (descriptor_ < 0) {
    throw IoError("cannot open '" + path.string() + "': " + std::strerror(errno));
  }
  struct stat status {};
  if (::fstat(descriptor_, &status) != 0) {
    const int error = errno;
    ::close(descriptor_);
    throw IoError("cannot read '" + path.string() + "': " + std::strerror(error));
  }
  if (!S_ISREG(status.st_mode)) {
    ::close(descriptor_);
    require_regular_file(path);  // throws, naming what it is
    throw IoError("cannot read '" + path.string() + "': not a regular file");
  }
  ::fcntl(descriptor_, F_SETFL, ::fcntl(descriptor_, F_GETFL) & ~O_NONBLOCK);
  size_ = static_cast<std::uint64_t>(status.st_size);
  // A small file needs no large block (one byte more than it holds sees its end in one read);
  // the buffer still grows if the file does.
  capacity_ = static_cast<std::size_t>(std::min<std::uint64_t>(capacity_, std::max<std::uint64_t>(size_ + 1, 4096)));
  // The kernel reads ahead more aggressively for a file declared sequential.
  ::posix_fadvise(descriptor_, 0, 0, POSIX_FADV_SEQUENTIAL);
  buffer_ = std::make_unique_for_overwrite<char[]>(capacity_);
}

InputFile::~InputFile() {
  if (descriptor_ >= 0) ::close(descriptor_);
}

void InputFile::fail_long_line() const {
  throw FormatError(path_.string() + ": line " + std::to_string(line_ + 1) + " is longer than " +
                    std::to_string(kLongestLine >> 20) + " MiB (is it a text file?)");
}

void InputFile::fill() {
  if (eof_) return;
  if (begin_ > 0) {
    std::memmove(buffer_.get(), buffer_.get() + begin_, end_ - begin_);
    end_ -= begin_;
    begin_ = 0;
  }
  // A line or record longer than the block: grow instead of failing.
  if (end_ == capacity_) grow(capacity_ * 2);
  for (;;) {
    const ssize_t got = ::read(descriptor_, buffer_.get() + end_, capacity_ - end_);
    if (got < 0) {
      if (errno == EINTR) continue;
      throw IoError("cannot read '" + path_.string() + "' at byte " +
                    std::to_string(consumed_ + (end_ - begin_)) + ": " + std::strerror(errno));
    }
    if (got == 0) eof_ = true;
    end_ += static_cast<std::size_t>(got);
    return;
  }
}

void InputFile::grow(std::size_t minimum) {
  std::size_t capacity = capacity_;
  while (capacity < minimum) capacity *= 2;
  auto larger = std::make_unique_for_overwrite<char[]>(capacity);
  std::memcpy(larger.get(), buffer_.get() + begin_, end_ - begin_);
  end_ -= begin_;
  begin_ = 0;
  buffer_ = std::move(larger);
  capacity_ = capacity;
}

void InputFile::fill_at_least(std::size_t count) {
  while (end_ - begin_ < count && !eof_) {
    if (capacity_ < count) grow(count);
    fill();
  }
}

}  // namespace tetrapage::detail
