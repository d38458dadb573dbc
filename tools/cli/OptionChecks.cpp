// CLI11 validators shared by the subcommands (Commands.h).

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "Commands.h"
#include "tetrapage/formats/ByteSize.h"
#include "tetrapage/formats/Error.h"

namespace tetrapage::cli {

CLI::Validator byte_size_check() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        try {
          (void)parse_byte_size(text);
          return {};
        } catch (const Error& error) {
          return error.what();
        }
      },
      "SIZE", "byte size");
}

CLI::Option* add_memory_option(CLI::App* command, std::string& memory, const std::string& purpose) {
  memory = byte_size_text(kDefaultMemoryBudget);
  // A purpose written in lines (as preprocess's help is) gets the sizes on a line of their own.
  const char* separator = purpose.find('\n') == std::string::npos ? ". " : ".\n";
  return command
      ->add_option("--memory", memory,
                   purpose + separator +
                       "Sizes as 512M or 4G: k, M, G, T are KiB, MiB, GiB, TiB (powers of 1024; "
                       "kB, MB, GB, TB too); no suffix: bytes")
      ->capture_default_str()
      ->check(byte_size_check());
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
      "INT in [" + std::to_string(lowest) + ", " + std::to_string(highest) + "]", "whole number range");
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
