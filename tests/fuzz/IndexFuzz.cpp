// The index reader on arbitrary bytes (IndexRead.h says what is read). Most of a small index
// is HDF5's metadata, so most inputs exercise HDF5's own decoding of damaged files as much as
// ours; IndexDataFuzz.cpp keeps the metadata intact and changes the data instead.

#include "FuzzSupport.h"
#include "IndexRead.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static tetrapage::fuzz::TempFile file(".tpi");
  file.write(data, size);
  tetrapage::fuzz::read_whole_index(file.path());
  return 0;
}
