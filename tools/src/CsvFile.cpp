#include "tetrapage/tools/CsvFile.h"

#include <cstdio>

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

std::string point_fields(const std::array<double, 3>& point) {
  std::string fields = number_field(point[0]);
  fields.append(1, ',')
      .append(number_field(point[1]))
      .append(1, ',')
      .append(number_field(point[2]));
  return fields;
}

CsvFile::CsvFile(const std::filesystem::path& path, const std::string& header) : out_(path) {
  out_.write(header);
  out_.write("\n", 1);
}

void CsvFile::commit() {
  out_.commit();
}

}  // namespace tetrapage
