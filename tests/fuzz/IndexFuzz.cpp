// The index reader on arbitrary bytes (IndexRead.h says what is read). Most of a small index
// is HDF5's metadata, so most inputs exercise HDF5's own decoding of damaged files as much as
// ours. The bytes are opened in memory (IndexReader over an image, HDF5's core driver), not
// written to a file. IndexDataFuzz.cpp keeps the metadata intact and changes the data instead.

#include "FuzzSupport.h"
#include "IndexRead.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  tetrapage::fuzz::read_whole_index(data, size);  // opened in memory: HDF5's core driver
  return 0;
}
