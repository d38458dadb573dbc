#include "VertexTable.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "tetrapage/formats/base/Error.h"

namespace tetrapage::detail {
namespace {

std::string system_error() { return std::strerror(errno); }

}  // namespace

VertexTable::~VertexTable() {
  if (file_ >= 0) ::close(file_);
}

void VertexTable::limit(std::uint64_t held, const std::filesystem::path& folder,
                        std::uint64_t cache_bytes) {
  held_limit_ = held;
  folder_ = folder;
  cache_bytes_ = cache_bytes;
}

void VertexTable::reserve(std::uint64_t count) {
  held_.reserve(std::size_t(std::min(count, held_limit_)));
}

// Unlinked from the start (O_TMPFILE, or made and removed at once): nothing is left behind
// however the process ends.
void VertexTable::open_file() {
  const std::filesystem::path folder = folder_.empty() ? std::filesystem::temp_directory_path() : folder_;
#ifdef O_TMPFILE
  file_ = ::open(folder.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
#endif
  if (file_ < 0) {
    std::string name = (folder / ".tetrapage-vertices-XXXXXX").string();
    file_ = ::mkstemp(name.data());
    if (file_ >= 0) ::unlink(name.c_str());
  }
  if (file_ < 0)
    throw IoError(folder.string() + ": cannot make a temporary file for a vertex table: " + system_error());
  const std::uint64_t slots = std::max<std::uint64_t>(cache_bytes_ / (kBlockVertices * sizeof(Vec3)), 1);
  cache_.resize(std::size_t(slots));
  tail_.reserve(kBlockVertices);
}

void VertexTable::write_tail() {
  const std::uint64_t block = (spilled() - tail_.size()) / kBlockVertices;
  const auto bytes = static_cast<std::size_t>(tail_.size() * sizeof(Vec3));
  const auto offset = static_cast<off_t>(block * kBlockVertices * sizeof(Vec3));
  const char* data = reinterpret_cast<const char*>(tail_.data());
  for (std::size_t written = 0; written < bytes;) {
    const ssize_t n = ::pwrite(file_, data + written, bytes - written, offset + off_t(written));
    if (n <= 0) {
      if (n < 0 && errno == EINTR) continue;
      throw IoError(folder_.string() + ": cannot write a vertex table's temporary file (disk full?): " +
                    system_error());
    }
    written += std::size_t(n);
  }
  tail_.clear();
}

void VertexTable::push_back(const Vec3& p) {
  ++size_;
  if (held_.size() < held_limit_) {
    // Grown within the limit: doubling past it would hold twice what the budget allows.
    if (held_.size() == held_.capacity() && held_limit_ != ~std::uint64_t(0))
      held_.reserve(std::size_t(std::min<std::uint64_t>(held_limit_, 2 * held_.size() + 1024)));
    held_.push_back(p);
    return;
  }
  if (file_ < 0) open_file();
  tail_.push_back(p);
  if (tail_.size() == kBlockVertices) write_tail();
}

Vec3 VertexTable::at(std::uint64_t i) {
  if (i < held_.size()) return held_[std::size_t(i)];
  const std::uint64_t s = i - held_.size();
  const std::uint64_t block = s / kBlockVertices, first_unwritten = spilled() - tail_.size();
  if (s >= first_unwritten) return tail_[std::size_t(s - first_unwritten)];
  Slot& slot = cache_[std::size_t(block % cache_.size())];
  if (slot.block != block) {
    slot.vertices.resize(kBlockVertices);
    const auto bytes = static_cast<std::size_t>(kBlockVertices * sizeof(Vec3));
    const auto offset = static_cast<off_t>(block * bytes);
    char* data = reinterpret_cast<char*>(slot.vertices.data());
    for (std::size_t read = 0; read < bytes;) {
      const ssize_t n = ::pread(file_, data + read, bytes - read, offset + off_t(read));
      if (n <= 0) {
        if (n < 0 && errno == EINTR) continue;
        slot.block = ~std::uint64_t(0);
        throw IoError(folder_.string() + ": cannot read back a vertex table's temporary file: " +
                      (n == 0 ? std::string("it ends early") : system_error()));
      }
      read += std::size_t(n);
    }
    slot.block = block;
  }
  return slot.vertices[std::size_t(s % kBlockVertices)];
}

void VertexTable::clear() {
  held_.clear();
  tail_.clear();
  for (Slot& slot : cache_) slot.block = ~std::uint64_t(0);
  size_ = 0;
  if (file_ >= 0 && ::ftruncate(file_, 0) != 0)
    throw IoError(folder_.string() + ": cannot empty a vertex table's temporary file: " + system_error());
}

}  // namespace tetrapage::detail
