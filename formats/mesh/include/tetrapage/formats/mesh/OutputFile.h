#pragma once
/// @file OutputFile.h
/// An output written under a temporary name through a large buffer, every system call checked
/// (a full disk is an IoError naming the output, never a silently short file), and renamed over
/// the output only when complete. The temporary is removed on destruction (and by the signal
/// handlers of TemporaryFiles.h) unless it was renamed.

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

#include "tetrapage/formats/base/TemporaryFiles.h"

namespace tetrapage {

class OutputFile {
 public:
  /// Checks `output` (FileChecks.h: a regular file or nothing), removes the temporaries that
  /// killed writers left beside it and creates temporary_path(output); commit() renames it.
  /// @throw InputError or IoError naming the output.
  explicit OutputFile(std::filesystem::path output);
  /// Creates (truncates) the temporary `path`, not followed if it is a link. `output` is the
  /// name the user asked for, used in messages. @throw IoError if it cannot be created.
  OutputFile(std::filesystem::path path, std::filesystem::path output);
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  void write(const void* data, std::size_t size) {
    if (capacity_ - used_ < size) {
      flush();
      if (size >= capacity_) {
        write_direct(data, size);
        return;
      }
    }
    std::memcpy(buffer_.get() + used_, data, size);
    used_ += size;
  }
  void write(std::string_view text) { write(text.data(), text.size()); }

  /// Room for `size` bytes (size <= 64 KiB) to format into; then advance() by what was used.
  char* reserve(std::size_t size) {
    if (capacity_ - used_ < size) flush();
    return buffer_.get() + used_;
  }
  void advance(std::size_t size) { used_ += size; }

  /// Bytes written so far, buffered ones included.
  std::uint64_t size() const { return written_ + used_; }

  /// Overwrites bytes already written (flushes first).
  void write_at(std::uint64_t offset, const void* data, std::size_t size);
  /// Appends the whole content of another output file (flushed first).
  void append_file(OutputFile& other);
  /// Flushes, closes and renames to `final_path`; the file is then no longer removed.
  /// @throw IoError if a write, the close or the rename fails.
  void rename_to(const std::filesystem::path& final_path);
  /// rename_to the output named at construction.
  void commit() { rename_to(output_); }

  void flush();

 private:
  void write_direct(const void* data, std::size_t size);
  [[noreturn]] void fail(const std::string& action, int error) const;

  std::filesystem::path path_;
  std::filesystem::path output_;
  TemporaryFileGuard guard_;  ///< SIGINT/SIGTERM remove the temporary
  int descriptor_ = -1;
  bool renamed_ = false;
  std::unique_ptr<char[]> buffer_;
  std::size_t capacity_ = 1u << 20;
  std::size_t used_ = 0;
  std::uint64_t written_ = 0;
};

}  // namespace tetrapage
