#include "TessellationArguments.h"


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
  set_deflection(options, deflection, "--deflection");
  options.angular_deflection = angular_deflection;
  options.skip_bad_parts = skip_bad_parts;
  options.show_progress = show_progress;
  return options;
}

}  // namespace tetrapage::cli
