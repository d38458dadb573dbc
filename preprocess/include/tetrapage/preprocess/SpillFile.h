#pragma once
/// @file SpillFile.h
/// A temporary file the preprocess spills to: created (empty) when made and unlinked at once,
/// so its name never outlives the call that made it, and its space is freed when it is
/// destroyed or the process ends, however; a failed read or write is an IoError that names it.

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>

#include "tetrapage/formats/base/Error.h"

namespace tetrapage {

class SpillFile {
 public:
  SpillFile() = default;
  /// @throw IoError when the file cannot be created.
  explicit SpillFile(std::filesystem::path path) : path_(std::move(path)) { open(); }
  ~SpillFile() { remove(); }
  SpillFile(SpillFile&&) noexcept = default;
  SpillFile& operator=(SpillFile&& other) noexcept {
    if (this != &other) {
      remove();
      path_ = std::move(other.path_);
      file_ = std::move(other.file_);
    }
    return *this;
  }

  explicit operator bool() const { return bool(file_); }

  /// @throw IoError when the write fails (a full disk).
  void write(const void* data, std::size_t size, std::size_t count) {
    if (count > 0 && std::fwrite(data, size, count, file_.get()) != count)
      throw IoError(path_.string() + ": cannot write to the spill file (disk full?)");
  }
  /// @throw IoError when the file holds fewer.
  void read(void* data, std::size_t size, std::size_t count) {
    if (count > 0 && std::fread(data, size, count, file_.get()) != count)
      throw IoError(path_.string() + ": the spill file ends early");
  }
  /// To the start for reading (what was written is flushed).
  void rewind() {
    if (std::fflush(file_.get()) != 0 || std::fseek(file_.get(), 0, SEEK_SET) != 0)
      throw IoError(path_.string() + ": cannot rewind the spill file");
  }
  /// To the end for appending.
  void seek_end() {
    if (std::fseek(file_.get(), 0, SEEK_END) != 0) throw IoError(path_.string() + ": cannot seek the spill file");
  }
  /// Empties the file, keeping it.
  void truncate() { open(); }
  const std::filesystem::path& path() const { return path_; }
  [[noreturn]] void damaged() const { throw IoError(path_.string() + ": the spill file is damaged"); }

 private:
  void open() {
    file_.reset(std::fopen(path_.c_str(), "w+b"));
    if (!file_) throw IoError(path_.string() + ": cannot create a spill file");
    // Unlinked at once: the open stream keeps the data, and nothing is left behind however the
    // process ends (an exception, Ctrl-C, a kill).
    std::error_code ignored;
    std::filesystem::remove(path_, ignored);
  }
  void remove() { file_.reset(); }

  struct FileCloser {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };
  std::filesystem::path path_;
  std::unique_ptr<std::FILE, FileCloser> file_;
};

}  // namespace tetrapage
