#pragma once
// Internal: locale-independent number parsing and printing for the text formats.
// std::from_chars / std::to_chars are exact: a double printed in the shortest form reads
// back bit for bit, which is what makes OBJ/PLY/OFF round trips exact.

#include <charconv>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>
#include <system_error>

#include "tetrapage/formats/base/QuotedInput.h"

namespace tetrapage::detail {

inline bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

inline void skip_spaces(std::string_view& text) {
  std::size_t i = 0;
  while (i < text.size() && is_space(text[i])) ++i;
  text.remove_prefix(i);
}

/// The next whitespace-separated token of `text` (empty when none is left); `text` is advanced.
inline std::string_view next_token(std::string_view& text) {
  skip_spaces(text);
  std::size_t i = 0;
  while (i < text.size() && !is_space(text[i])) ++i;
  const std::string_view token = text.substr(0, i);
  text.remove_prefix(i);
  return token;
}

/// Parses the whole token as a double (a leading '+' is accepted; "nan" and "inf" parse, the
/// caller rejects them with the value in the message). False if the token is not a number.
inline bool parse_double(std::string_view token, double& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
  // from_chars rejects 1e999 and 1e-999 as out of range and leaves `value` alone; strtod
  // (rare path, the program never changes the "C" locale) gives +-inf, which the caller
  // rejects with the value in the message, or the underflowed value.
  if (error == std::errc::result_out_of_range && end == token.data() + token.size()) {
    value = std::strtod(std::string(token).c_str(), nullptr);
    return true;
  }
  return error == std::errc() && end == token.data() + token.size() && !token.empty();
}

/// Parses the whole token as a signed integer.
inline bool parse_integer(std::string_view token, std::int64_t& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
  return error == std::errc() && end == token.data() + token.size() && !token.empty();
}

/// Parses the whole token as an unsigned integer.
inline bool parse_unsigned(std::string_view token, std::uint64_t& value) {
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
  return error == std::errc() && end == token.data() + token.size() && !token.empty();
}

/// Largest length of a double printed by append_double (shortest round-trip form).
constexpr std::size_t max_double_chars = 32;

/// Writes the shortest text that reads back as exactly `value`; returns the end.
inline char* write_double(char* out, double value) {
  return std::to_chars(out, out + max_double_chars, value).ptr;
}

inline void append_double(std::string& text, double value) {
  char buffer[max_double_chars];
  text.append(buffer, write_double(buffer, value));
}

/// A token quoted for an error message: cut short if very long, unprintable bytes escaped.
inline std::string quote_token(std::string_view token) {
  return quoted_input(token);
}

}  // namespace tetrapage::detail
