#include "TessellationArguments.h"

#include <cmath>

#include "tetrapage/formats/Error.h"

namespace tetrapage::cli {

void TessellationArguments::add_to(CLI::App* command) {
  command
      ->add_option(
          "--deflection", deflection,
          "STEP/IGES tessellation: the largest distance between a triangle and the surface it "
          "stands for, as a percentage of each shape's bounding-box diagonal (0.1%) or as a length "
          "in millimetres, the unit STEP and IGES are read in (0.01)")
      ->capture_default_str();
  command
      ->add_option(
          "--angular-deflection", angular_deflection,
          "STEP/IGES tessellation: the largest angle in radians between the surface's normals "
          "along a triangle's edge")
      ->capture_default_str();
  command->add_flag(
      "--skip-bad-parts", skip_bad_parts,
      "Leave out STEP/IGES shapes that fail to tessellate, and list them, instead of failing");
}

TessellationOptions TessellationArguments::options(bool show_progress) const {
  TessellationOptions options;
  std::string text = deflection;
  options.relative_deflection = !text.empty() && text.back() == '%';
  if (options.relative_deflection) text.pop_back();
  std::size_t used = 0;
  double value = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || text.empty() || !(value > 0) || !std::isfinite(value))
    throw InputError("--deflection '" + deflection +
                     "': expected a positive length (0.01) or percentage (0.1%)");
  options.deflection = options.relative_deflection ? value / 100 : value;
  options.angular_deflection = angular_deflection;
  options.skip_bad_parts = skip_bad_parts;
  options.show_progress = show_progress;
  return options;
}

}  // namespace tetrapage::cli
