#include "tetrapage/tools/CsvFile.h"

#include <cstdio>
#include <span>

#include "tetrapage/formats/Error.h"
#include "tetrapage/formats/FileChecks.h"

namespace tetrapage {

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string quoted = "\"";
  for (const char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

std::string number_field(double value) {
  char text[40];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

CsvFile::CsvFile(const std::filesystem::path& path, const std::string& header, std::string what)
    : path_(path), temporary_(path.string() + ".tmp"), what_(std::move(what)) {
  check_outputs(std::span<const std::filesystem::path>(&path, 1), {});
  guard_.emplace(temporary_);
  out_.open(temporary_, std::ios::binary);
  if (!out_) throw IoError("cannot create " + what_ + " '" + temporary_.string() + "'");
  out_ << header << '\n';
}

CsvFile::~CsvFile() {
  if (committed_) return;
  out_.close();
  std::error_code ignored;
  std::filesystem::remove(temporary_, ignored);
}

void CsvFile::commit() {
  if (!out_.flush()) throw IoError("cannot write " + what_ + " '" + temporary_.string() + "' (disk full?)");
  out_.close();
  std::error_code error;
  std::filesystem::rename(temporary_, path_, error);
  if (error) throw IoError("cannot rename " + what_ + " to '" + path_.string() + "': " + error.message());
  committed_ = true;
}

}  // namespace tetrapage
