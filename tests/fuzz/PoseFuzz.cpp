// The pose file reader (CSV tx,ty,tz,qw,qx,qy,qz) on arbitrary bytes.

#include <cmath>

#include "FuzzSupport.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/Pose.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static tetrapage::fuzz::TempFile file(".csv");
  file.write(data, size);
  try {
    for (const tetrapage::Pose& pose : tetrapage::read_poses(file.path())) {
      // read_poses promises finite poses with a normalisable quaternion.
      for (const double value : pose.translation)
        if (!std::isfinite(value)) __builtin_trap();
      for (const double value : pose.rotation)
        if (!std::isfinite(value)) __builtin_trap();
    }
  } catch (const tetrapage::Error&) {
  }
  return 0;
}
