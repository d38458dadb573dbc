// The assembly manifest parser (JSON) on arbitrary bytes: a manifest or a tetrapage::Error.

#include "FuzzSupport.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/Manifest.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static tetrapage::fuzz::TempFile file(".json");
  file.write(data, size);
  try {
    const tetrapage::Manifest manifest = tetrapage::read_manifest(file.path());
    if (manifest.parts.empty()) __builtin_trap();  // read_manifest rejects an empty assembly
    for (const auto& part : manifest.parts)
      if (part.instances.empty()) __builtin_trap();
  } catch (const tetrapage::Error&) {
  }
  return 0;
}
