// The dynamic obstacles file (DynamicObstacles::load) on arbitrary bytes, against a small index
// of the seed corpus: a FormatError or an overlay whose parts all lie on the index.

#include "FuzzSupport.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/runtime/paging/CollisionIndex.h"
#include "tetrapage/runtime/query/DynamicObstacles.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const auto index =
      std::make_shared<const tetrapage::CollisionIndex>(std::filesystem::path(TETRAPAGE_FUZZ_INDEX));
  static tetrapage::fuzz::TempFile file(".tpo");
  file.write(data, size);
  try {
    const tetrapage::DynamicObstacles overlay = tetrapage::DynamicObstacles::load(index, file.path());
    for (const auto& part : overlay.parts())
      if (part.id == tetrapage::kNoDynamicPart || part.name.find('\n') != std::string::npos) __builtin_trap();
  } catch (const tetrapage::Error&) {
  }
  return 0;
}
