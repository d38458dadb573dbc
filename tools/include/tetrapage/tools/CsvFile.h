#pragma once
/// @file CsvFile.h
/// A CSV output written under a temporary name and renamed into place by commit(): a run that
/// fails leaves no partial file behind.

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>

#include "tetrapage/formats/mesh/OutputFile.h"

namespace tetrapage {

/// A field, quoted when it holds a comma, a quote or a line break.
std::string csv_field(const std::string& text);
/// A number with all its digits (%.17g: reads back to the same double).
std::string number_field(double value);
/// A point as three number fields, "x,y,z".
std::string point_fields(const std::array<double, 3>& point);

class CsvFile {
 public:
  /// Opens `path` under a temporary name (OutputFile.h) and writes `header` (without the line
  /// break); the temporary is removed unless commit() ran. @throw InputError or IoError.
  CsvFile(const std::filesystem::path& path, const std::string& header);

  /// One row (its fields joined by commas already).
  void row(const std::string& fields) {
    out_.write(fields);
    out_.write("\n", 1);
    ++rows_;
  }
  std::uint64_t rows() const { return rows_; }
  /// Flushes and renames the file into place. @throw IoError.
  void commit();

 private:
  OutputFile out_;
  std::uint64_t rows_ = 0;
};

}  // namespace tetrapage
