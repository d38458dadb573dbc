// The index reader on valid HDF5 files whose data is damaged: the input edits the bytes of a
// seed index that HDF5 does not interpret (every stored chunk of the shards, the mesh, the
// extents and the tables) and the Fletcher-32 of each edited chunk is made right again, so
// that the damage reaches our checks (extents, tables, the chunk codec, Shard::decode) instead
// of stopping at a checksum or in HDF5's decoding of its own metadata (fuzz_index's lot).
// Input: one byte choosing the seed, then edits of 4 bytes each (a 24-bit position in the
// seed's data, a byte); the empty input is the seed as it is.

#include <hdf5.h>

#include <fstream>
#include <iterator>
#include <string>

#include "ChunkCodec.h"
#include "FuzzSupport.h"
#include "IndexRead.h"

namespace {

/// A stored chunk: its bytes (the last 4 its checksum) in the file.
struct Region {
  std::uint64_t offset = 0;
  std::uint64_t bytes = 0;
};

struct Seed {
  std::string file;
  std::vector<Region> regions;  ///< the data, without checksums, in file order
  std::uint64_t data_bytes = 0;
};

/// The stored chunks of a chunked dataset, through HDF5's chunk index.
void add_chunks(hid_t file, const char* name, std::vector<Region>& regions) {
  const hid_t dataset = H5Dopen2(file, name, H5P_DEFAULT);
  if (dataset < 0) return;
  const hid_t space = H5Dget_space(dataset);
  hsize_t count = 0;
  if (H5Dget_num_chunks(dataset, space, &count) >= 0)
    for (hsize_t i = 0; i < count; ++i) {
      hsize_t offset[2] = {0, 0};
      unsigned mask = 0;
      haddr_t address = HADDR_UNDEF;
      hsize_t size = 0;
      if (H5Dget_chunk_info(dataset, space, i, offset, &mask, &address, &size) >= 0 &&
          address != HADDR_UNDEF && size > 4)
        regions.push_back({address, size});
    }
  H5Sclose(space);
  H5Dclose(dataset);
}

herr_t add_table(hid_t group, const char* name, const H5L_info_t*, void* regions) {
  add_chunks(group, name, *static_cast<std::vector<Region>*>(regions));
  return 0;
}

Seed load_seed(const std::string& path) {
  Seed seed;
  std::ifstream in(path, std::ios::binary);
  seed.file.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) std::abort();
  for (const char* name : {"/mesh/vertices", "/mesh/tets", "/mesh/neighbours", "/shards/offsets",
                           "/shards/sizes", "/shards/data"})
    add_chunks(file, name, seed.regions);
  const hid_t tables = H5Gopen2(file, "/tables", H5P_DEFAULT);
  hsize_t index = 0;
  H5Literate(tables, H5_INDEX_NAME, H5_ITER_INC, &index, add_table, &seed.regions);
  H5Gclose(tables);
  H5Fclose(file);
  for (Region& region : seed.regions) {
    region.bytes -= tetrapage::detail::kChecksumBytes;
    seed.data_bytes += region.bytes;
  }
  return seed;
}

std::vector<Seed> load_seeds() {
  std::vector<Seed> seeds;
  for (const char* name : {"tetra.tpi", "sphere-float-grid.tpi", "sphere-uncompressed.tpi"})
    seeds.push_back(load_seed(std::string(TETRAPAGE_FUZZ_INDEX_SEEDS) + "/" + name));
  return seeds;
}

/// The seed with the input's edits applied and the edited chunks' checksums made right.
std::string edited(const Seed& seed, const std::uint8_t* edits, std::size_t size) {
  std::string file = seed.file;
  std::vector<bool> touched(seed.regions.size(), false);
  for (std::size_t at = 0; at + 4 <= size && seed.data_bytes > 0; at += 4) {
    std::uint64_t position =
        (edits[at] | edits[at + 1] << 8 | edits[at + 2] << 16) % seed.data_bytes;
    for (std::size_t r = 0; r < seed.regions.size(); ++r) {
      if (position >= seed.regions[r].bytes) {
        position -= seed.regions[r].bytes;
        continue;
      }
      file[seed.regions[r].offset + position] = static_cast<char>(edits[at + 3]);
      touched[r] = true;
      break;
    }
  }
  for (std::size_t r = 0; r < seed.regions.size(); ++r) {
    if (!touched[r]) continue;
    const Region& region = seed.regions[r];
    const auto* bytes = reinterpret_cast<const std::byte*>(file.data() + region.offset);
    const std::uint32_t checksum = tetrapage::detail::fletcher32({bytes, region.bytes});
    for (int i = 0; i < 4; ++i)
      file[region.offset + region.bytes + i] = static_cast<char>((checksum >> (8 * i)) & 0xff);
  }
  return file;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::vector<Seed> seeds = load_seeds();
  const Seed& seed = seeds[size == 0 ? 0 : data[0] % seeds.size()];
  const std::string bytes = size == 0 ? seed.file : edited(seed, data + 1, size - 1);
  tetrapage::fuzz::read_whole_index(reinterpret_cast<const std::uint8_t*>(bytes.data()),
                                    bytes.size());
  return 0;
}
