#pragma once
/// @file CsvFile.h
/// A CSV output written under a temporary name and renamed into place by commit(): a run that
/// fails leaves no partial file behind.

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

#include "tetrapage/formats/TemporaryFiles.h"

namespace tetrapage {

/// A field, quoted when it holds a comma, a quote or a line break.
std::string csv_field(const std::string& text);
/// A number with all its digits (%.17g: reads back to the same double).
std::string number_field(double value);

class CsvFile {
 public:
  /// Opens `path` under a temporary name and writes `header` (without the line break).
  /// `what` names the file in errors ("contacts file"). @throw IoError.
  CsvFile(const std::filesystem::path& path, const std::string& header, std::string what);
  /// Removes the temporary unless commit() ran.
  ~CsvFile();
  CsvFile(const CsvFile&) = delete;
  CsvFile& operator=(const CsvFile&) = delete;

  /// One row (its fields joined by commas already).
  void row(const std::string& fields) {
    out_ << fields << '\n';
    ++rows_;
  }
  std::uint64_t rows() const { return rows_; }
  /// Flushes and renames the file into place. @throw IoError.
  void commit();

 private:
  std::filesystem::path path_, temporary_;
  std::string what_;
  std::optional<TemporaryFileGuard> guard_;
  std::ofstream out_;
  std::uint64_t rows_ = 0;
  bool committed_ = false;
};

}  // namespace tetrapage
