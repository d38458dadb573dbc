#pragma once
// The options of every command that reads STEP or IGES: how B-rep shapes become triangles.

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>

#include "tetrapage/formats/mesh/CadReader.h"

namespace tetrapage::cli {

struct TessellationArguments {
  std::string deflection = "0.1%";
  double angular_deflection = TessellationOptions{}.angular_deflection;
  bool skip_bad_parts = false;
  std::uint64_t max_occurrences = TessellationOptions{}.max_occurrences;
  std::uint64_t max_triangles = TessellationOptions{}.max_triangles;
  double time_limit = TessellationOptions{}.time_limit;
  std::string memory_limit;  // empty: the library's default

  /// Adds --deflection, --angular-deflection, --max-cad-occurrences, --max-cad-triangles, --cad-timeout,
  /// --cad-memory and --skip-bad-parts to `command`.
  void add_to(CLI::App* command);
  /// @throw InputError for a deflection that is not a positive length or percentage.
  TessellationOptions options(bool show_progress) const;
};

}  // namespace tetrapage::cli
