// The answer file reader (CSV step,collides) on arbitrary bytes.

#include "FuzzSupport.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/tools/AnswerFile.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static tetrapage::fuzz::TempFile file(".csv");
  file.write(data, size);
  try {
    for (const std::uint8_t answer : tetrapage::read_answers(file.path()))
      if (answer > 1) __builtin_trap();
  } catch (const tetrapage::Error&) {
  }
  return 0;
}
