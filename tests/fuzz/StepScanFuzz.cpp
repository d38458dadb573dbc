// The STEP pre-scan (formats/mesh/src/StepPrescan.h) on arbitrary bytes, fed whole and in pieces:
// it must finish without a crash or an unbounded allocation, and read the same either way.

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "StepPrescan.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  tetrapage::detail::StepScanner whole;
  whole.feed(bytes);
  const tetrapage::detail::StepStructure once = whole.finish();
  // The same bytes in pieces of a size the input chooses.
  const std::size_t piece = size == 0 ? 1 : 1 + data[0] % 13;
  tetrapage::detail::StepScanner pieces;
  for (std::size_t at = 0; at < size; at += piece) pieces.feed(bytes.substr(at, piece));
  const tetrapage::detail::StepStructure again = pieces.finish();
  if (once.instances != again.instances || once.cycle != again.cycle ||
      once.assembly_depth != again.assembly_depth ||
      once.assembly_occurrences != again.assembly_occurrences)
    __builtin_trap();
  // An entity takes at least "#1=A;" (5 bytes); an occurrence record more.
  if (once.instances > size / 5 + 1 || once.assembly_occurrences > size) __builtin_trap();
  return 0;
}
