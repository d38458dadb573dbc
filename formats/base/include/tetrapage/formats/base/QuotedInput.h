#pragma once
/// @file QuotedInput.h
/// Text read from an input, as an error message quotes it.

#include <cstddef>
#include <string>
#include <string_view>

namespace tetrapage {

/// `text` between single quotes, cut after `limit` characters ("...'"), every byte that is not
/// printable ASCII written as \xNN: a message stays one short line of text whatever a file holds
/// (binary bytes, a NUL that would end it, a line break that would split it).
inline std::string quoted_input(std::string_view text, std::size_t limit = 40) {
  static const char digits[] = "0123456789abcdef";
  std::string quoted(1, '\'');
  std::size_t shown = 0;
  for (const char c : text) {
    if (shown == limit) {
      quoted.append("...");
      break;
    }
    const auto byte = static_cast<unsigned char>(c);
    if (byte >= 0x20 && byte < 0x7f) {
      quoted.push_back(c);
    } else {
      quoted.append("\\x");
      quoted.push_back(digits[byte >> 4]);
      quoted.push_back(digits[byte & 15]);
    }
    ++shown;
  }
  quoted.push_back('\'');
  return quoted;
}

}  // namespace tetrapage
