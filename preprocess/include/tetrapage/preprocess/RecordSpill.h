#pragma once
/// @file RecordSpill.h
/// An append-then-read sequence of trivially copyable records in a temporary spill file: how
/// the preprocess keeps the binned copies of a large model out of memory (docs/ARCHITECTURE.md).
/// The file is removed when the spill is destroyed (also on errors).

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <span>
#include <type_traits>
#include <vector>

#include "tetrapage/preprocess/SpillFile.h"

namespace tetrapage {

template <class Record>
class RecordSpill {
  static_assert(std::is_trivially_copyable_v<Record>);

 public:
  /// @throw IoError when the file cannot be created.
  explicit RecordSpill(std::filesystem::path file) : file_(std::move(file)) {}

  std::uint64_t size() const { return count_; }

  /// @throw IoError when a write fails (disk full).
  void append(std::span<const Record> records) {
    count_ += records.size();
    file_.write(records.data(), sizeof(Record), records.size());
  }

  /// Calls visit(std::span<const Record>) on consecutive blocks of at most block_records,
  /// in append order.
  /// @throw IoError when the file cannot be read back.
  template <class Visit>
  void for_each_block(std::size_t block_records, Visit&& visit) {
    if (block_records == 0) block_records = 1;
    file_.rewind();
    std::vector<Record> block(std::min<std::uint64_t>(block_records, count_));
    for (std::uint64_t left = count_; left > 0;) {
      const std::size_t n = std::size_t(std::min<std::uint64_t>(left, block.size()));
      file_.read(block.data(), sizeof(Record), n);
      visit(std::span<const Record>(block.data(), n));
      left -= n;
    }
    file_.seek_end();
  }

  /// All records, read into memory (the caller knows they fit).
  std::vector<Record> read_all() {
    std::vector<Record> all;
    all.reserve(count_);
    for_each_block(1 << 16, [&](std::span<const Record> block) {
      all.insert(all.end(), block.begin(), block.end());
    });
    return all;
  }

  /// Frees the records (and truncates the file).
  void clear() {
    count_ = 0;
    file_.truncate();
  }

 private:
  SpillFile file_;
  std::uint64_t count_ = 0;
};

}  // namespace tetrapage
