// STEP or IGES reading (the extension is TETRAPAGE_FUZZ_EXTENSION) on arbitrary bytes through
// read_cad: the pre-scan in this process, OpenCASCADE in its child, whose crash, hang or
// runaway allocation must come back as a tetrapage::Error. Slow (a process per input): not
// in `make fuzz`'s default targets.

#include "FuzzSupport.h"
#include "tetrapage/formats/CadReader.h"
#include "tetrapage/formats/Error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static tetrapage::fuzz::TempFile file(TETRAPAGE_FUZZ_EXTENSION);
  file.write(data, size);
  tetrapage::TessellationOptions options;
  options.time_limit = 10;
  options.memory_limit = std::uint64_t(1) << 30;
  options.max_triangles = 1'000'000;
  try {
    const tetrapage::TriangleSoup soup = tetrapage::read_cad(file.path(), options);
    for (const auto& triangle : soup.triangles)
      for (const std::uint32_t corner : triangle)
        if (corner >= soup.vertices.size()) __builtin_trap();
    if (soup.part_of.size() != soup.triangles.size()) __builtin_trap();
  } catch (const tetrapage::Error&) {
  }
  return 0;
}
