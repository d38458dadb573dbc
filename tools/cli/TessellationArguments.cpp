#include "TessellationArguments.h"

#include <cmath>

#include "Commands.h"
#include "tetrapage/formats/base/ByteSize.h"
#include "tetrapage/formats/base/Error.h"

namespace tetrapage::cli {
namespace {

// The coarsest tessellation asked for that still means something: the whole shape (100%), or a
// kilometre.
constexpr double kLargestRelativeDeflection = 1.0, kLargestDeflectionMillimetres = 1e6;

// --deflection as set_deflection reads it, in a range, checked while the command line is read
// so that a bad value is a command-line mistake.
CLI::Validator deflection_check() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        TessellationOptions options;
        try {
          set_deflection(options, text, "--deflection");
        } catch (const Error&) {
          options.deflection = 0;
        }
        const double largest = options.relative_deflection ? kLargestRelativeDeflection
                                                           : kLargestDeflectionMillimetres;
        if (!(options.deflection > 0) || options.deflection > largest)
          return "'" + text + "' is not a length in (0, 1e6] mm nor a percentage in (0, 100]%";
        return {};
      },
      "LENGTH or PERCENT%", "deflection");
}

}  // namespace

void TessellationArguments::add_to(CLI::App* command) {
  command
      ->add_option(
          "--deflection", deflection,
          "STEP/IGES tessellation: the largest distance between a triangle and the surface it "
          "stands for, as a percentage of each shape's bounding-box diagonal (0.1%) or as a length "
          "in millimetres, the unit STEP and IGES are read in (0.01)")
      ->capture_default_str()
      ->check(deflection_check());
  command
      ->add_option(
          "--angular-deflection", angular_deflection,
          "STEP/IGES tessellation: the largest angle in radians between the surface's normals "
          "along a triangle's edge")
      ->capture_default_str()
      ->check(positive_number_check(3.14159265358979));
  command
      ->add_option("--max-cad-occurrences", max_occurrences,
                   "STEP: refuse files with more placed components than this (0: no limit); "
                   "OpenCASCADE reads them in time quadratic in their number")
      ->capture_default_str()
      ->check(whole_number_check(0, 1'000'000'000));
  command
      ->add_option(
          "--max-cad-triangles", max_triangles,
          "STEP/IGES: refuse a file whose tessellation would make more triangles than this "
          "(estimated before meshing at a deflection finer than the default; 0: no limit)")
      ->capture_default_str()
      ->check(whole_number_check(0, 1'000'000'000'000));
  command
      ->add_option(
          "--cad-timeout", time_limit,
          "STEP/IGES: seconds the reading and tessellation of one file may take (0: no limit)")
      ->capture_default_str()
      ->check(number_check(0, 1e7));
  command
      ->add_option("--cad-memory", memory_limit,
                   "STEP/IGES: memory the reading of one file may take (512M, 4G); default: "
                   "the machine's memory")
      ->check(byte_size_check());
  command->add_flag(
      "--skip-bad-parts", skip_bad_parts,
      "Leave out STEP/IGES shapes that fail to tessellate, and list them, instead of failing");
}

TessellationOptions TessellationArguments::options(bool show_progress) const {
  TessellationOptions options;
  set_deflection(options, deflection, "--deflection");
  options.angular_deflection = angular_deflection;
  options.skip_bad_parts = skip_bad_parts;
  options.show_progress = show_progress;
  options.max_occurrences = max_occurrences;
  options.max_triangles = max_triangles;
  if (!(time_limit >= 0) || !std::isfinite(time_limit))
    throw InputError("--cad-timeout " + std::to_string(time_limit) +
                     ": expected seconds, 0 or more");
  options.time_limit = time_limit;
  if (!memory_limit.empty()) options.memory_limit = parse_byte_size(memory_limit);
  return options;
}

}  // namespace tetrapage::cli
