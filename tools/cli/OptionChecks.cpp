// CLI11 validators shared by the subcommands (Commands.h).

#include <sys/stat.h>
#include <algorithm>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <optional>
#include <string>

#include "Commands.h"
#include "tetrapage/formats/base/ByteSize.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/QuotedInput.h"

namespace tetrapage::cli {

CLI::Validator byte_size_check(std::uint64_t minimum) {
  return CLI::Validator(
      [minimum](std::string& text) -> std::string {
        try {
          if (parse_byte_size(text) < minimum)
            return "'" + text + "' is below the least size, " + byte_size_text(minimum);
          return {};
        } catch (const Error& error) {
          return error.what();
        }
      },
      "SIZE", "byte size");
}

CLI::Option* add_memory_option(CLI::App* command, std::string& memory, const std::string& purpose,
                               std::uint64_t minimum) {
  memory = byte_size_text(kDefaultMemoryBudget);
  // A purpose written in lines (as preprocess's help is) gets the sizes on a line of their own.
  const char* separator = purpose.find('\n') == std::string::npos ? ". " : ".\n";
  return command
      ->add_option("--memory", memory,
                   purpose + separator +
                       "Sizes as 512M or 4G: k, M, G, T are KiB, MiB, GiB, TiB (powers of 1024; "
                       "kB, MB, GB, TB too); no suffix: bytes")
      ->capture_default_str()
      ->check(byte_size_check(minimum));
}

CLI::Validator whole_number_check(long long lowest, long long highest) {
  const std::string range = "a whole number from " + std::to_string(lowest) + " to " + std::to_string(highest);
  return CLI::Validator(
      [lowest, highest, range](std::string& text) -> std::string {
        char* end = nullptr;
        errno = 0;
        const long long value = std::strtoll(text.c_str(), &end, 10);
        if (text.empty() || *end != 0 || errno != 0 || value < lowest || value > highest)
          return "'" + text + "' is not " + range;
        return {};
      },
      "in [" + std::to_string(lowest) + ", " + std::to_string(highest) + "]", "whole number range");
}

namespace {

// "1000", "0.001", "1e+06": short enough for the help's type column.
std::string number_text(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

// The value `text` spells in full as a finite decimal number (a leading '+' allowed), or none.
std::optional<double> finite_number(const std::string& text) {
  const char* first = text.c_str();
  const char* last = first + text.size();
  if (first != last && *first == '+') ++first;
  double value = 0;
  const auto [end, error] = std::from_chars(first, last, value);
  if (first == last || error != std::errc() || end != last || !std::isfinite(value)) return {};
  return value;
}

CLI::Validator number_range_check(double lowest, double highest, bool lowest_included) {
  const std::string range =
      (lowest_included ? "[" : "(") + number_text(lowest) + ", " + number_text(highest) + "]";
  return CLI::Validator(
      [lowest, highest, lowest_included, range](std::string& text) -> std::string {
        const std::optional<double> value = finite_number(text);
        if (!value || *value > highest || *value < lowest || (!lowest_included && *value == lowest))
          return "'" + text + "' is not a number in " + range;
        return {};
      },
      "in " + range, "number range");
}

}  // namespace

CLI::Validator number_check(double lowest, double highest) {
  return number_range_check(lowest, highest, true);
}

CLI::Validator positive_number_check(double highest) {
  return number_range_check(0, highest, false);
}

CLI::Validator seed_check() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        std::uint64_t value = 0;
        const char* last = text.c_str() + text.size();
        const auto [end, error] = std::from_chars(text.c_str(), last, value);
        if (text.empty() || error != std::errc() || end != last)
          return "'" + text + "' is not a whole number from 0 to " +
                 std::to_string(std::numeric_limits<std::uint64_t>::max());
        return {};
      },
      "in [0, 2^64-1]", "seed");
}

CLI::Validator parsed_by(std::function<void(const std::string&)> parse, const std::string& name) {
  return CLI::Validator(
      [parse](std::string& text) -> std::string {
        try {
          parse(text);
          return {};
        } catch (const Error& error) {
          return error.what();
        }
      },
      name, "parsed by the library");
}

void refuse_empty_values(CLI::App& command) {
  const CLI::Validator not_empty(
      [](std::string& text) -> std::string {
        return text.empty() ? "an empty value names nothing" : std::string();
      },
      "", "not empty");
  for (CLI::Option* option : command.get_options())
    if (option->get_type_size() != 0) option->check(not_empty);
  for (CLI::App* subcommand : command.get_subcommands([](CLI::App*) { return true; }))
    refuse_empty_values(*subcommand);
}

CLI::Validator existing_file_check() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        struct stat status {};
        if (::stat(text.c_str(), &status) != 0) {
          const int error = errno;
          const std::string quoted = quoted_input(text, 200);
          if (error == ELOOP) return quoted + " is a loop of symbolic links";
          if (error == ENOENT) return quoted + " does not exist";
          return quoted + ": " + std::strerror(error);
        }
        if (S_ISDIR(status.st_mode)) return quoted_input(text, 200) + " is a folder, not a file";
        return {};
      },
      "FILE", "existing file");
}

CLI::Validator image_size_check() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        int width = 0, height = 0, used = 0;
        if (std::sscanf(text.c_str(), "%dx%d%n", &width, &height, &used) != 2 || used != int(text.size()) ||
            width < 1 || height < 1 || width > 16384 || height > 16384)
          return "'" + text + "' is not WIDTHxHEIGHT with each side from 1 to 16384";
        return {};
      },
      "WIDTHxHEIGHT", "image size");
}

}  // namespace tetrapage::cli
