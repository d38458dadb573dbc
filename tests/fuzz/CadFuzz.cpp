// STEP or IGES reading (the extension is TETRAPAGE_FUZZ_EXTENSION) on arbitrary bytes through
// TessellatedFile: the pre-scan in this process, OpenCASCADE in its child, whose crash, hang or
// runaway allocation must come back as a tetrapage::Error; then its instances placed whole and
// in chunks of 3 triangles, which must succeed or fail alike and give the same triangles, parts
// and skipped parts. Slow (a process per input): not in `make fuzz`'s default targets.

#include <optional>

#include "ChunkedRead.h"
#include "FuzzSupport.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/TessellatedFile.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static tetrapage::fuzz::TempFile file(TETRAPAGE_FUZZ_EXTENSION);
  file.write(data, size);
  tetrapage::TessellationOptions options;
  options.time_limit = 10;
  options.memory_limit = std::uint64_t(1) << 30;
  options.max_triangles = 1'000'000;
  options.skip_bad_parts = size % 2 == 0;  // both ways, on inputs alike
  tetrapage::ReadReport read;
  std::optional<tetrapage::TessellatedFile> tessellated;
  try {
    tessellated.emplace(file.path(), options, read);
  } catch (const tetrapage::Error&) {
    return 0;
  }
  tetrapage::ReadReport whole_report = read, chunked_report = read;
  std::optional<tetrapage::TriangleSoup> whole;
  try {
    whole = tessellated->place(whole_report);
    tetrapage::fuzz::check_soup(*whole);
  } catch (const tetrapage::Error&) {
  }
  std::optional<tetrapage::fuzz::ChunkedRead> chunked(std::in_place);
  tetrapage::SoupChunks chunks;
  chunks.triangles = 3;
  chunked->collect_from(chunks);
  try {
    chunked->names = tessellated->place_in_chunks(chunks, chunked_report);
  } catch (const tetrapage::Error&) {
    chunked.reset();
  }
  if (whole.has_value() != chunked.has_value()) __builtin_trap();
  if (!whole) return 0;
  tetrapage::fuzz::check_same_soup(*chunked, *whole);
  if (chunked_report.triangles_read != whole_report.triangles_read ||
      chunked_report.degenerate_dropped != whole_report.degenerate_dropped ||
      chunked_report.skipped_parts != whole_report.skipped_parts)
    __builtin_trap();
  return 0;
}
