// Hostile index files: a few bytes edited in a real index (a dataset's extent, a string's
// length, the header's values) must be rejected at open by a one-line FormatError naming the
// file, the dataset or attribute and the value, before anything is sized by them (each case
// runs in a child whose address space is capped); a shard whose file was truncated or changed
// under a running reader says so.

#include <hdf5.h>
#include <sys/stat.h>

#include <cmath>
#include <functional>
#include <limits>

#include "../MemoryLimit.h"
#include "Hdf5Metadata.h"
#include "TestSupport.h"
#include "tetrapage/formats/index/IndexReader.h"
#include "tetrapage/formats/index/IndexWriter.h"

namespace tetrapage {
namespace {

using test::ChildOutcome;
using test::run_with_memory_limit;
using test::scratch_folder;

constexpr std::uint32_t kChunk = 4096;

/// `action` must throw a FormatError in a memory-capped child, one line holding every part.
void expect_capped_format_error(const std::function<void()>& action, const std::vector<std::string>& parts) {
  const ChildOutcome outcome = run_with_memory_limit(action);
  EXPECT_EQ(outcome.kind, "FormatError") << outcome.message;
  for (const auto& part : parts)
    EXPECT_NE(outcome.message.find(part), std::string::npos)
        << "message '" << outcome.message << "' does not contain '" << part << "'";
  EXPECT_EQ(outcome.message.find('\n'), std::string::npos) << outcome.message;
}

struct SmallIndex {
  TetMesh mesh;
  std::vector<std::vector<std::byte>> shards;
  std::vector<double> shard_bounds;
  IndexHeader header;
};

/// A model in [0, 1]^3 with three shards, a coarse mesh around it in [-1, 2]^3 and the tables
/// the preprocess writes for shards and tets (and one of its own).
SmallIndex small_index() {
  SmallIndex index;
  Random random(31);
  for (double x : {-1.0, 2.0})
    for (double y : {-1.0, 2.0})
      for (double z : {-1.0, 2.0}) index.mesh.vertices.push_back({x, y, z});
  for (std::uint32_t t = 0; t < 6; ++t) {
    index.mesh.tets.push_back({t, t + 1, t + 2, 7});
    index.mesh.neighbours.push_back({TetMesh::no_neighbour, t == 5 ? TetMesh::no_neighbour : t + 1,
                                     TetMesh::no_neighbour, TetMesh::no_neighbour});
  }
  for (std::size_t size : {100u, 5000u, 9000u}) {
    std::vector<std::byte> shard(size);
    for (std::size_t i = 0; i < size; ++i) shard[i] = std::byte(random.below(16) == 0 ? random.below(256) : i % 7);
    index.shards.push_back(std::move(shard));
  }
  index.shard_bounds = {0, 0, 0, 0.5, 0.5, 0.5, 0.25, 0, 0, 1, 1, 1, 0, 0.5, 0, 1, 1, 0.5};
  index.header.precision = "double";
  index.header.region_count = index.mesh.tet_count();
  index.header.bounds.extend(Vec3{0, 0, 0});
  index.header.bounds.extend(Vec3{1, 1, 1});
  index.header.source = "small";
  index.header.build_report_json = "{\"pad\":\"" + std::string(77777 - 10, 'x') + "\"}";  // 77777 bytes
  return index;
}

std::filesystem::path write_index(const std::filesystem::path& path, const SmallIndex& index) {
  IndexWriter writer(path, {.chunk_bytes = kChunk});
  writer.write_mesh(index.mesh);
  std::vector<std::uint32_t> tet_shard(index.mesh.tet_count(), 0);
  tet_shard[1] = 1;
  tet_shard[2] = 2;
  writer.write_table("tet_shard", std::span<const std::uint32_t>(tet_shard));
  const std::vector<std::uint8_t> kinds(index.shards.size(), 1);
  writer.write_table("shard_kind", std::span<const std::uint8_t>(kinds));
  writer.write_table("shard_bounds", std::span<const double>(index.shard_bounds));
  const std::vector<double> weights(33, 0.5);
  writer.write_table("weights", std::span<const double>(weights));
  for (const auto& shard : index.shards) writer.append_shard(shard);
  writer.commit(index.header);
  return path;
}

/// Opens the file with HDF5 and changes it.
void edit(const std::filesystem::path& path, const std::function<void(hid_t file)>& change) {
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  change(file);
  H5Fclose(file);
}

void set_extent(hid_t file, const char* name, std::vector<hsize_t> dims) {
  const hid_t dataset = H5Dopen2(file, name, H5P_DEFAULT);
  ASSERT_GE(dataset, 0) << name;
  EXPECT_GE(H5Dset_extent(dataset, dims.data()), 0) << name;
  H5Dclose(dataset);
}

void set_u64_attribute(hid_t file, const char* name, std::uint64_t value) {
  const hid_t attribute = H5Aopen_by_name(file, "/", name, H5P_DEFAULT, H5P_DEFAULT);
  ASSERT_GE(attribute, 0) << name;
  EXPECT_GE(H5Awrite(attribute, H5T_NATIVE_UINT64, &value), 0);
  H5Aclose(attribute);
}

TEST(IndexLimits, TheIndexReadsBackAsWritten) {
  const auto folder = scratch_folder("good");
  const SmallIndex index = small_index();
  const IndexReader reader(write_index(folder / "model.tpi", index));
  EXPECT_EQ(reader.header().build_report_json.size(), 77777u);
  for (std::uint32_t s = 0; s < reader.shard_count(); ++s) EXPECT_EQ(reader.read_shard(s), index.shards[s]);
  EXPECT_EQ(reader.read_table_double("shard_bounds"), index.shard_bounds);
  EXPECT_TRUE(reader.validate().empty());
}

TEST(IndexLimits, OversizedDatasetExtentsAreRejectedBeforeAllocating) {
  const auto folder = scratch_folder("extents");
  const SmallIndex index = small_index();
  const auto path = folder / "model.tpi";
  const auto open = [&] { IndexReader reader(path); };
  for (const hsize_t extent : {hsize_t{1} << 26, hsize_t{1} << 40}) {
    SCOPED_TRACE("extent " + std::to_string(extent));
    const std::string value = std::to_string(extent);
    for (const char* name : {"/shards/sizes", "/shards/offsets"}) {
      write_index(path, index);
      edit(path, [&](hid_t file) { set_extent(file, name, {extent}); });
      expect_capped_format_error(open, {"model.tpi", name, value, "expected 3", "'shard_count'"});
    }
    // The attribute and both tables agree, but not with the file's size.
    write_index(path, index);
    edit(path, [&](hid_t file) {
      set_u64_attribute(file, "shard_count", extent);
      set_extent(file, "/shards/offsets", {extent});
      set_extent(file, "/shards/sizes", {extent});
    });
    if (extent < 0xffffffffu)
      expect_capped_format_error(open, {"model.tpi", "/shards/offsets", value, "rows", "file can hold"});
    else
      expect_capped_format_error(open, {"model.tpi", "'shard_count'", value, "2^32 - 1"});
    write_index(path, index);
    edit(path, [&](hid_t file) { set_extent(file, "/mesh/vertices", {extent, 3}); });
    expect_capped_format_error(open, {"model.tpi", "/mesh/vertices", value, "file can hold"});
    write_index(path, index);
    edit(path, [&](hid_t file) {
      set_extent(file, "/mesh/tets", {extent, 4});
      set_extent(file, "/mesh/neighbours", {extent, 4});
    });
    expect_capped_format_error(open, {"model.tpi", "/mesh/tets", value, "file can hold"});
    write_index(path, index);
    edit(path, [&](hid_t file) { set_extent(file, "/shards/data", {extent}); });
    expect_capped_format_error(open, {"model.tpi", "/shards/data", value, "file can hold"});
    // A table the preprocess writes has the length the shards give it; any table is bounded
    // by the file when it is read.
    write_index(path, index);
    edit(path, [&](hid_t file) { set_extent(file, "/tables/shard_kind", {extent}); });
    expect_capped_format_error(open, {"model.tpi", "/tables/shard_kind", value, "expected 3"});
    write_index(path, index);
    edit(path, [&](hid_t file) { set_extent(file, "/tables/weights", {extent}); });
    expect_capped_format_error([&] { IndexReader(path).read_table_double("weights"); },
                               {"model.tpi", "/tables/weights", value, "file can hold"});
  }
}

/// Offsets in the file of `value` stored as 4 little-endian bytes.
std::vector<std::size_t> find_u32(const std::string& bytes, std::uint32_t value) {
  std::vector<std::size_t> found;
  for (std::size_t i = 0; i + 4 <= bytes.size(); ++i)
    if (std::memcmp(bytes.data() + i, &value, 4) == 0) found.push_back(i);
  return found;
}

std::uint64_t load_u64(const std::string& bytes, std::size_t at) {
  std::uint64_t value = 0;
  std::memcpy(&value, bytes.data() + at, 8);
  return value;
}

TEST(IndexLimits, StringAttributeClaimingGigabytesIsRejected) {
  const auto folder = scratch_folder("strings");
  const auto path = write_index(folder / "model.tpi", small_index());
  const std::string original = test::read_file(path);
  // The build report's length is stored twice: in the attribute (then the address of its heap
  // collection) and in the heap object (then the string's bytes).
  std::size_t in_attribute = 0, in_heap = 0;
  for (const std::size_t at : find_u32(original, 77777)) {
    const std::uint64_t address = at + 12 <= original.size() ? load_u64(original, at + 4) : 0;
    if (address + 4 <= original.size() && original.compare(address, 4, "GCOL") == 0)
      in_attribute = at;
    else if (original.compare(at + 8, 8, "{\"pad\":\"") == 0)
      in_heap = at;
  }
  ASSERT_NE(in_attribute, 0u);
  ASSERT_NE(in_heap, 0u);
  const auto patched = [&](std::size_t at, std::uint32_t value) {
    std::string bytes = original;
    std::memcpy(bytes.data() + at, &value, 4);
    if (at == in_attribute) test::reseal_metadata(original, bytes, at, 4);  // a crafted file
    test::write_file(path, bytes);
  };
  const auto open = [&] { IndexReader reader(path); };
  // Without its checksum made right, the edit is refused by HDF5 as damaged metadata.
  {
    std::string bytes = original;
    const std::uint32_t value = 0x7fffffffu;
    std::memcpy(bytes.data() + in_attribute, &value, 4);
    test::write_file(path, bytes);
    expect_capped_format_error(open, {"model.tpi", "checksum"});
  }
  patched(in_attribute, 0x7fffffffu);
  expect_capped_format_error(open, {"model.tpi", "'build_report'", "2147483647 bytes", "file holds"});
  patched(in_attribute, 77776);
  expect_capped_format_error(open, {"model.tpi", "'build_report'", "global heap", "77777 bytes, not 77776"});
  // The heap object's own size: HDF5 1.10 reads past its collection (a crash) on these.
  patched(in_heap, 0x7fffffffu);
  expect_capped_format_error(open, {"model.tpi", "'build_report'", "global heap", "2147483647"});
  patched(in_heap, 10);
  expect_capped_format_error(open, {"model.tpi", "'build_report'", "global heap"});
}

// Found by fuzz_index: HDF5 allocates and reads a filtered chunk at the size its chunk index
// claims, gigabytes in a small file. The index (an extensible array) stores each chunk as its
// address, then its stored size in as few bytes as the chunk's size needs, then the filter mask.
TEST(IndexLimits, ChunkIndexClaimingGigabytesIsRejected) {
  const auto folder = scratch_folder("chunk_index");
  const auto path = write_index(folder / "model.tpi", small_index());
  haddr_t address = 0;
  hsize_t stored = 0;
  edit(path, [&](hid_t file) {
    const hid_t dataset = H5Dopen2(file, "/tables/weights", H5P_DEFAULT);
    const hsize_t origin[2] = {0, 0};
    unsigned mask = 0;
    ASSERT_GE(H5Dget_chunk_info_by_coord(dataset, origin, &mask, &address, &stored), 0);
    H5Dclose(dataset);
  });
  const std::string original = test::read_file(path);
  std::string record(8, '\0');
  std::memcpy(record.data(), &address, 8);
  record.push_back(static_cast<char>(stored & 0xff));
  record.push_back(static_cast<char>((stored >> 8) & 0xff));
  const std::size_t at = original.find(record);
  ASSERT_NE(at, std::string::npos);
  ASSERT_EQ(original.find(record, at + 1), std::string::npos);
  std::string bytes = original;
  const std::array<unsigned char, 3> huge{0x00, 0x00, 0xf0};  // 15,728,640 bytes, in a 3-byte size
  std::memcpy(bytes.data() + at + 8, huge.data(), huge.size());
  test::reseal_metadata(original, bytes, at + 8, huge.size());
  test::write_file(path, bytes);
  expect_capped_format_error([&] { IndexReader(path).read_table_double("weights"); },
                             {"model.tpi", "'/tables/weights'", "stores the chunk", "15728640"});
}

TEST(IndexLimits, ShardOfAFileTruncatedUnderTheReaderSaysSo) {
  const auto folder = scratch_folder("truncated");
  const auto path = write_index(folder / "model.tpi", small_index());
  const auto whole = std::filesystem::file_size(path);
  for (const bool located : {false, true}) {
    SCOPED_TRACE(located ? "chunks located" : "direct chunk reads");
    write_index(path, small_index());
    const IndexReader reader(path);
    const auto last = reader.shard_chunks(2);
    if (!located) {
      // A fresh reader, which has not located its chunks.
      const IndexReader fresh(path);
      std::filesystem::resize_file(path, last.front().file_offset);
      test::expect_error<FormatError>([&] { fresh.read_shard(2); },
                                      {"model.tpi", "the file changed or is truncated", "shard 2"});
      continue;
    }
    std::filesystem::resize_file(path, last.front().file_offset);
    test::expect_error<FormatError>([&] { reader.read_shard(2); },
                                    {"model.tpi", "the file changed or is truncated", "shard 2",
                                     std::to_string(whole) + " when opened"});
  }
  // Zeros where a chunk was stored, in a file opened that way: zeros pass the checksum.
  write_index(path, small_index());
  StoredChunk chunk;
  {
    const IndexReader reader(path);
    chunk = reader.shard_chunks(1).front();
  }
  std::string bytes = test::read_file(path);
  std::fill_n(bytes.begin() + std::ptrdiff_t(chunk.file_offset), chunk.stored_bytes, '\0');
  test::write_file(path, bytes);
  const IndexReader reader(path);
  try {
    reader.read_shard(1);
    ADD_FAILURE() << "no exception";
  } catch (const FormatError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("model.tpi"), std::string::npos) << message;
    EXPECT_NE(message.find("the file changed or is truncated: shard 1"), std::string::npos) << message;
    EXPECT_NE(message.find("zeros"), std::string::npos) << message;
    EXPECT_EQ(message.find("decodes to 0 bytes"), std::string::npos) << message;
  }
}

TEST(IndexLimits, HeaderAttributesAreCheckedAgainstTheData) {
  const auto folder = scratch_folder("header");
  const auto path = folder / "model.tpi";
  const auto rejected = [&](const std::function<void(SmallIndex&)>& change, const std::vector<std::string>& parts) {
    SmallIndex index = small_index();
    change(index);
    write_index(path, index);
    std::vector<std::string> all = parts;
    all.push_back("model.tpi");
    test::expect_error<FormatError>([&] { IndexReader reader(path); }, all);
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  rejected([&](SmallIndex& i) { i.header.bounds.hi[1] = nan; }, {"'bounds'", "nan", "axis y"});
  rejected([](SmallIndex& i) { i.header.bounds.lo[2] = 1.5; }, {"'bounds'", "inverted", "axis z", "1.5"});
  rejected([](SmallIndex& i) { i.header.bounds.hi[0] = 3; }, {"'bounds'", "coarse mesh", "axis x", "3"});
  rejected([](SmallIndex& i) { i.shard_bounds[4] = 1.25; }, {"'bounds'", "shard 0", "1.25", "shard_bounds"});
  rejected([](SmallIndex& i) { i.header.bounds = BoundingBox{}; }, {"'bounds'", "empty", "shard 0"});
  rejected([&](SmallIndex& i) { i.header.max_rounding_distance = nan; }, {"'max_rounding_distance'", "nan"});
  rejected([](SmallIndex& i) { i.header.max_rounding_distance = -1; }, {"'max_rounding_distance'", "-1"});
  rejected([](SmallIndex& i) { i.header.max_rounding_distance = 1e-7; },
           {"'max_rounding_distance'", "1e-07", "'double'", "expected 0"});
  rejected(
      [](SmallIndex& i) {
        i.header.precision = "exact";
        i.header.max_rounding_distance = 1e-7;
      },
      {"'max_rounding_distance'", "'exact'"});
  // Rounded to floats, a shard's box may pass the bounds by the rounding distance.
  SmallIndex rounded = small_index();
  rounded.header.precision = "float";
  rounded.header.max_rounding_distance = 1e-7;
  rounded.shard_bounds[3] = 0.5;
  rounded.shard_bounds[0] = -0.9e-7;
  write_index(path, rounded);
  EXPECT_NO_THROW(IndexReader reader(path));
  // A precision the writer refuses, set with HDF5.
  edit(path, [](hid_t file) {
    H5Adelete(file, "precision");
    const hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, 6);
    const hid_t space = H5Screate(H5S_SCALAR);
    const hid_t attribute = H5Acreate2(file, "precision", type, space, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(attribute, type, "single");
    H5Aclose(attribute);
    H5Sclose(space);
    H5Tclose(type);
  });
  test::expect_error<FormatError>([&] { IndexReader reader(path); }, {"model.tpi", "'precision'", "'single'"});
}

}  // namespace
}  // namespace tetrapage
