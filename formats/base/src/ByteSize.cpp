#include "tetrapage/formats/base/ByteSize.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>

#include "tetrapage/formats/base/Error.h"

namespace tetrapage {

std::uint64_t parse_byte_size(std::string_view text) {
  std::string quoted(1, '\'');  // built by append: GCC 12 warns falsely on "'" + string
  quoted.append(text);
  quoted.push_back('\'');
  double value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || !std::isfinite(value) || value < 0)
    throw InputError("not a byte size: " + quoted + " (examples: 512M, 2G, 1000000)");
  std::string suffix(end, text.data() + text.size());
  for (char& c : suffix) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (suffix.ends_with("ib")) suffix.resize(suffix.size() - 2);
  else if (suffix.size() == 2 && suffix[1] == 'b') suffix.resize(1);
  double scale = 1;
  if (suffix.empty() || suffix == "b") scale = 1;
  else if (suffix == "k") scale = 0x1p10;
  else if (suffix == "m") scale = 0x1p20;
  else if (suffix == "g") scale = 0x1p30;
  else if (suffix == "t") scale = 0x1p40;
  else throw InputError("unknown size unit in " + quoted + " (use k, M, G or T)");
  const double bytes = std::round(value * scale);
  if (bytes >= 0x1p63) throw InputError("byte size too large: " + quoted);
  return static_cast<std::uint64_t>(bytes);
}

std::string format_byte_size(std::uint64_t bytes) {
  static const char* const units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  double value = double(bytes);
  int unit = 0;
  while (value >= 1024 && unit < 4) value /= 1024, ++unit;
  char text[32];
  std::snprintf(text, sizeof text, unit == 0 ? "%.0f %s" : "%.1f %s", value, units[unit]);
  return text;
}

std::string byte_size_text(std::uint64_t bytes) {
  static const char suffixes[] = {'k', 'M', 'G', 'T'};
  int unit = -1;
  while (unit < 3 && bytes != 0 && bytes % 1024 == 0) bytes /= 1024, ++unit;
  return unit < 0 ? std::to_string(bytes) : std::to_string(bytes) + suffixes[unit];
}

}  // namespace tetrapage
