// One mesh reader (the format is chosen by TETRAPAGE_FUZZ_EXTENSION: .ply, .obj, .stl, .off)
// on arbitrary bytes: it must return a soup or throw a tetrapage::Error, nothing else.

#include "FuzzSupport.h"
#include "tetrapage/formats/Error.h"
#include "tetrapage/formats/MeshReader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static tetrapage::fuzz::TempFile file(TETRAPAGE_FUZZ_EXTENSION);
  file.write(data, size);
  try {
    const tetrapage::TriangleSoup soup = tetrapage::read_mesh(file.path());
    // What every caller relies on: indices in range, one part per triangle.
    for (const auto& triangle : soup.triangles)
      for (const std::uint32_t corner : triangle)
        if (corner >= soup.vertices.size()) __builtin_trap();
    if (soup.part_of.size() != soup.triangles.size()) __builtin_trap();
  } catch (const tetrapage::Error&) {
  }
  return 0;
}
