#pragma once
// Internal: a file read front to back in large blocks, so that readers never hold the whole
// file in memory. Text readers take it line by line (views into the block), binary readers
// take fixed-size records; both are views that stay valid until the next call.

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <string_view>

namespace tetrapage::detail {

/// The longest line a text reader takes (a face of a million corners fits): a file of one
/// endless line (/dev/zero's kind, or a binary file named .obj) fails instead of filling memory.
inline constexpr std::size_t kLongestLine = std::size_t(64) << 20;

class InputFile {
 public:
  /// @throw IoError if the file cannot be opened or is not a regular file.
  explicit InputFile(const std::filesystem::path& path, std::size_t block_size = 4u << 20);
  ~InputFile();
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::string name() const { return path_.string(); }
  /// Size of the file when it was opened.
  std::uint64_t size() const { return size_; }
  /// Bytes handed out so far (the offset of the next byte a caller will see).
  std::uint64_t offset() const { return consumed_; }
  /// 1-based number of the line last returned by next_line().
  std::uint64_t line_number() const { return line_; }

  /// The next line without its end ('\n' or "\r\n"); false at the end of the file.
  /// @throw IoError on a read failure; FormatError for a line longer than kLongestLine.
  bool next_line(std::string_view& line) {
    for (;;) {
      const char* first = buffer_.get() + begin_;
      const auto* newline = static_cast<const char*>(std::memchr(first, '\n', end_ - begin_));
      if (newline != nullptr) {
        std::size_t length = static_cast<std::size_t>(newline - first);
        consume(length + 1);
        if (length > 0 && first[length - 1] == '\r') --length;
        line = std::string_view(first, length);
        ++line_;
        return true;
      }
      if (eof_) {
        if (begin_ == end_) return false;
        std::size_t length = end_ - begin_;
        consume(length);
        if (first[length - 1] == '\r') --length;
        line = std::string_view(first, length);
        ++line_;
        return true;
      }
      if (end_ - begin_ >= kLongestLine) fail_long_line();
      fill();
    }
  }

  /// Bytes of the file (as large as it was when opened) not handed out yet.
  std::uint64_t bytes_left() const { return size_ > consumed_ ? size_ - consumed_ : 0; }

  /// Up to `count` bytes (fewer only at the end of the file), consumed. A count beyond the
  /// file's end reads what is there: it never sizes the buffer (a header's claim may be huge).
  /// @throw IoError on a read failure.
  std::span<const char> take(std::size_t count) {
    if (end_ - begin_ < count) fill_at_least(capped(count));
    const std::size_t available = std::min(count, end_ - begin_);
    const char* first = buffer_.get() + begin_;
    consume(available);
    return {first, available};
  }

  /// Up to `count` bytes from the current position, not consumed.
  std::string_view peek(std::size_t count) {
    if (end_ - begin_ < count) fill_at_least(capped(count));
    return {buffer_.get() + begin_, std::min(count, end_ - begin_)};
  }

 private:
  /// `count`, or what the file held (when opened) past the bytes handed out, if less: what a
  /// read may wait for. Bytes already buffered stay available either way.
  std::size_t capped(std::size_t count) const {
    const std::uint64_t most = std::max<std::uint64_t>(end_ - begin_, bytes_left());
    return static_cast<std::size_t>(std::min<std::uint64_t>(count, most));
  }
  void consume(std::size_t count) {
    begin_ += count;
    consumed_ += count;
  }
  /// Moves the unread bytes to the front and reads one more block (growing the buffer when a
  /// single line or record does not fit).
  void fill();
  [[noreturn]] void fail_long_line() const;
  void fill_at_least(std::size_t count);
  void grow(std::size_t minimum);

  std::filesystem::path path_;
  int descriptor_ = -1;
  std::uint64_t size_ = 0;
  std::unique_ptr<char[]> buffer_;
  std::size_t capacity_ = 0;
  std::size_t begin_ = 0;
  std::size_t end_ = 0;
  bool eof_ = false;
  std::uint64_t consumed_ = 0;
  std::uint64_t line_ = 0;
};

}  // namespace tetrapage::detail
