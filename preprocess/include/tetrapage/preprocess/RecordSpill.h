#pragma once
/// @file RecordSpill.h
/// An append-then-read sequence of trivially copyable records, held in memory or spilled to a
/// temporary file: how the preprocess keeps its working memory bounded by --memory rather than
/// by the model. The file is removed when the spill is destroyed (also on errors).

#include <cstdio>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "tetrapage/formats/Error.h"
#include "tetrapage/preprocess/SpillFile.h"

namespace tetrapage {

template <class Record>
class RecordSpill {
  static_assert(std::is_trivially_copyable_v<Record>);

 public:
  /// In memory when `file` is empty; otherwise spilled to `file` (created, truncated).
  /// @throw IoError when the file cannot be created.
  explicit RecordSpill(std::filesystem::path file = {}) {
    if (!file.empty()) file_ = SpillFile(std::move(file));
  }

  bool spilled() const { return bool(file_); }

  /// Moves the records held in memory to `file` and spills from now on.
  /// @throw IoError when the file cannot be created or written.
  void spill_to(std::filesystem::path file) {
    if (file_) return;
    file_ = SpillFile(std::move(file));
    std::vector<Record> held;
    held.swap(memory_);
    count_ = 0;
    append(held);
  }
  std::uint64_t size() const { return count_; }

  /// @throw IoError when a write fails (disk full).
  void append(std::span<const Record> records) {
    count_ += records.size();
    if (!file_) {
      memory_.insert(memory_.end(), records.begin(), records.end());
      return;
    }
    file_.write(records.data(), sizeof(Record), records.size());
  }
  void append(const Record& record) { append(std::span<const Record>(&record, 1)); }

  /// Calls visit(std::span<const Record>) on consecutive blocks of at most block_records,
  /// in append order.
  /// @throw IoError when the file cannot be read back.
  template <class Visit>
  void for_each_block(std::size_t block_records, Visit&& visit) {
    if (block_records == 0) block_records = 1;
    if (!file_) {
      for (std::size_t first = 0; first < memory_.size(); first += block_records)
        visit(std::span<const Record>(memory_).subspan(
            first, std::min(block_records, memory_.size() - first)));
      return;
    }
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
    if (!file_) return memory_;
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
    std::vector<Record>().swap(memory_);
    if (file_) file_.truncate();
  }

 private:
  SpillFile file_;
  std::vector<Record> memory_;
  std::uint64_t count_ = 0;
};

}  // namespace tetrapage
