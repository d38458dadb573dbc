// The HDF5 index: round trips of mesh, tables and shards (both read paths, several threads),
// the temporary-file protocol, and files that are missing, foreign, of another version,
// truncated or corrupted. The chunk codec is checked against HDF5's own filters.

#include <hdf5.h>

#include <functional>
#include <thread>

#include "ChunkCodec.h"
#include "TestSupport.h"
#include "tetrapage/formats/index/IndexReader.h"
#include "tetrapage/formats/index/IndexWriter.h"

namespace tetrapage {
namespace {

using test::expect_error;
using test::scratch_folder;

std::vector<std::byte> random_bytes(Random& random, std::size_t size, bool compressible) {
  std::vector<std::byte> bytes(size);
  for (std::size_t i = 0; i < size; ++i)
    bytes[i] = std::byte(compressible ? (random.below(16) == 0 ? random.below(256) : (i / 7) % 5)
                                      : random.below(256));
  return bytes;
}

TetMesh random_mesh(Random& random, std::size_t vertices, std::size_t tets) {
  TetMesh mesh;
  for (std::size_t v = 0; v < vertices; ++v)
    mesh.vertices.push_back({random.uniform(-1e9, 1e9), random.uniform(-1, 1), random.normal()});
  for (std::size_t t = 0; t < tets; ++t) {
    std::array<std::uint32_t, 4> corners{}, neighbours{};
    for (int i = 0; i < 4; ++i) {
      corners[i] = static_cast<std::uint32_t>(random.below(vertices));
      neighbours[i] = random.below(5) == 0 ? TetMesh::no_neighbour
                                           : static_cast<std::uint32_t>(random.below(tets));
    }
    mesh.tets.push_back(corners);
    mesh.neighbours.push_back(neighbours);
  }
  return mesh;
}

IndexHeader sample_header() {
  IndexHeader header;
  header.precision = "float";
  header.input_triangles = 123456789012ULL;
  header.stored_triangles = 234567890123ULL;
  header.region_count = 120;  // write_sample's tets (the reader checks)
  header.max_rounding_distance = 1.5e-7;
  // Inside random_mesh's vertices (the reader checks that the coarse mesh covers the model).
  header.bounds.extend(Vec3{-1.25e8, -0.5, -0.25});
  header.bounds.extend(Vec3{4.0, 5e-9, 0.125});
  header.source = "scene.glb sha256:0123abcd é";
  // Larger than HDF5's 64 KiB limit for compact attributes.
  header.build_report_json = "{\"pad\":\"" + std::string(200000, 'x') + "\"}";
  return header;
}

constexpr std::uint32_t kChunk = 4096;

/// Payload sizes covering the edges: empty, one byte, exactly a chunk, one past, several.
std::vector<std::size_t> edge_sizes() {
  return {0, 1, kChunk, kChunk + 1, 3 * kChunk + 17, 2 * kChunk, 0, 100, 5 * kChunk - 1};
}

struct WrittenIndex {
  std::filesystem::path path;
  TetMesh mesh;
  std::vector<std::vector<std::byte>> shards;
  std::vector<std::uint32_t> tet_shard;
  std::vector<std::uint8_t> shard_kind;
  std::vector<std::uint64_t> ids;
  std::vector<double> weights;
  std::uint64_t file_bytes = 0;
};

WrittenIndex write_sample(const std::filesystem::path& folder, std::uint64_t seed) {
  WrittenIndex written;
  written.path = folder / "model.tpi";
  Random random(seed);
  written.mesh = random_mesh(random, 50, 120);
  for (std::size_t size : edge_sizes()) written.shards.push_back(random_bytes(random, size, true));
  written.shards.push_back(random_bytes(random, 2 * kChunk + 5, false));  // incompressible
  for (std::size_t t = 0; t < written.mesh.tet_count(); ++t)
    written.tet_shard.push_back(static_cast<std::uint32_t>(random.below(written.shards.size())));
  for (std::size_t s = 0; s < written.shards.size(); ++s)
    written.shard_kind.push_back(static_cast<std::uint8_t>(s % 2));
  for (int i = 0; i < 70000; ++i) written.ids.push_back(random.next_u64());
  for (int i = 0; i < 33; ++i) written.weights.push_back(random.normal());

  IndexWriter writer(written.path, {.chunk_bytes = kChunk});
  writer.write_mesh(written.mesh);
  writer.write_table("tet_shard", std::span<const std::uint32_t>(written.tet_shard));
  writer.write_table("shard_kind", std::span<const std::uint8_t>(written.shard_kind));
  writer.write_table("ids", std::span<const std::uint64_t>(written.ids));
  writer.write_table("weights", std::span<const double>(written.weights));
  writer.write_table("empty", std::span<const double>());
  for (std::size_t s = 0; s < written.shards.size(); ++s)
    EXPECT_EQ(writer.append_shard(written.shards[s]), s);
  written.file_bytes = writer.commit(sample_header());
  return written;
}

TEST(IndexFile, RoundTripOfMeshTablesAndShards) {
  const std::uint64_t seed = 20240511;
  SCOPED_TRACE("seed " + std::to_string(seed));
  const auto folder = scratch_folder("round_trip");
  const WrittenIndex written = write_sample(folder, seed);
  EXPECT_EQ(test::folder_listing(folder), std::vector<std::string>{"model.tpi"});
  EXPECT_EQ(written.file_bytes, std::filesystem::file_size(written.path));

  const IndexReader reader(written.path);
  const IndexHeader expected = sample_header();
  const IndexHeader& header = reader.header();
  EXPECT_EQ(header.version, kIndexVersion);
  EXPECT_EQ(header.precision, expected.precision);
  EXPECT_EQ(header.input_triangles, expected.input_triangles);
  EXPECT_EQ(header.stored_triangles, expected.stored_triangles);
  EXPECT_EQ(header.region_count, expected.region_count);
  EXPECT_EQ(header.shard_count, written.shards.size());
  EXPECT_EQ(header.max_rounding_distance, expected.max_rounding_distance);
  EXPECT_EQ(header.bounds.lo, expected.bounds.lo);
  EXPECT_EQ(header.bounds.hi, expected.bounds.hi);
  EXPECT_EQ(header.source, expected.source);
  EXPECT_EQ(header.build_report_json, expected.build_report_json);
  EXPECT_NE(header.created_by.find("tetrapage"), std::string::npos);
  EXPECT_EQ(reader.file_bytes(), written.file_bytes);

  const TetMesh mesh = reader.read_mesh();
  EXPECT_EQ(mesh.vertices, written.mesh.vertices);
  EXPECT_EQ(mesh.tets, written.mesh.tets);
  EXPECT_EQ(mesh.neighbours, written.mesh.neighbours);

  EXPECT_EQ(reader.table_names(),
            (std::vector<std::string>{"empty", "ids", "shard_kind", "tet_shard", "weights"}));
  EXPECT_TRUE(reader.has_table("tet_shard"));
  EXPECT_FALSE(reader.has_table("nothing"));
  EXPECT_EQ(reader.read_table_uint32("tet_shard"), written.tet_shard);
  EXPECT_EQ(reader.read_table_uint8("shard_kind"), written.shard_kind);
  EXPECT_EQ(reader.read_table_uint64("ids"), written.ids);
  EXPECT_EQ(reader.read_table_double("weights"), written.weights);
  EXPECT_TRUE(reader.read_table_double("empty").empty());
  expect_error<FormatError>([&] { reader.read_table_double("tet_shard"); },
                            {"model.tpi", "/tables/tet_shard", "uint32", "float64"});
  expect_error<FormatError>([&] { reader.read_table_uint8("nothing"); },
                            {"model.tpi", "/tables/nothing", "missing"});

  ASSERT_EQ(reader.shard_count(), written.shards.size());
  EXPECT_EQ(reader.chunk_bytes(), kChunk);
  std::uint64_t expected_offset = 0;
  for (std::uint32_t s = 0; s < reader.shard_count(); ++s) {
    SCOPED_TRACE("shard " + std::to_string(s));
    const auto& payload = written.shards[s];
    EXPECT_EQ(reader.shard_size(s), payload.size());
    EXPECT_EQ(reader.read_shard(s), payload);
    EXPECT_EQ(reader.read_shard_through_hdf5(s), payload);
    const auto chunks = reader.shard_chunks(s);
    ASSERT_EQ(chunks.size(), (payload.size() + kChunk - 1) / kChunk);
    std::uint64_t stored = 0;
    for (std::size_t k = 0; k < chunks.size(); ++k) {
      EXPECT_EQ(chunks[k].chunk, expected_offset / kChunk + k);  // shards are consecutive runs
      stored += chunks[k].stored_bytes;
    }
    EXPECT_EQ(reader.stored_shard_size(s), stored);
    expected_offset += chunks.size() * kChunk;
  }
  // The incompressible shard's full chunks are stored with LZ4 skipped; its last chunk,
  // mostly zero padding, and the other shards are compressed.
  const auto mixed = reader.shard_chunks(reader.shard_count() - 1);
  ASSERT_EQ(mixed.size(), 3u);
  EXPECT_FALSE(mixed[0].compressed);
  EXPECT_FALSE(mixed[1].compressed);
  EXPECT_TRUE(mixed[2].compressed);
  for (const auto& chunk : reader.shard_chunks(4)) EXPECT_TRUE(chunk.compressed);
  expect_error<InputError>([&] { reader.read_shard(reader.shard_count()); }, {"shard"});
  EXPECT_EQ(reader.validate(), std::vector<std::string>{});
}

TEST(IndexFile, ShardsReadConcurrentlyFromSeveralThreads) {
  const std::uint64_t seed = 77;
  SCOPED_TRACE("seed " + std::to_string(seed));
  const auto folder = scratch_folder("threads");
  const WrittenIndex written = write_sample(folder, seed);
  IndexReader reader(written.path);
  // Waits for the chunk read lock that poll (the default) and that sleep at once.
  for (const auto spin : {std::chrono::microseconds(100), std::chrono::microseconds(0)})
    for (int threads : {2, 4}) {
      reader.set_spin_before_sleep(spin);
      std::vector<int> mismatches(static_cast<std::size_t>(threads), 0);
      std::vector<std::thread> workers;
      for (int w = 0; w < threads; ++w)
        workers.emplace_back([&, w] {
          for (int round = 0; round < 20; ++round)
            for (std::uint32_t i = 0; i < reader.shard_count(); ++i) {
              // Different threads walk the shards in different orders.
              const auto s =
                  static_cast<std::uint32_t>((i * (2 * w + 1) + round) % reader.shard_count());
              const bool through_hdf5 = (round + w) % 2 == 1;
              const auto payload =
                  through_hdf5 ? reader.read_shard_through_hdf5(s) : reader.read_shard(s);
              if (payload != written.shards[s]) ++mismatches[static_cast<std::size_t>(w)];
            }
        });
      for (auto& worker : workers) worker.join();
      for (int w = 0; w < threads; ++w)
        EXPECT_EQ(mismatches[static_cast<std::size_t>(w)], 0)
            << threads << " threads, thread " << w << ", polling " << spin.count() << " us";
    }
}

TEST(IndexFile, WriterWithoutCommitLeavesNothing) {
  const auto folder = scratch_folder("no_commit");
  const auto target = folder / "model.tpi";
  std::filesystem::path temporary;
  {
    IndexWriter writer(target, {.chunk_bytes = kChunk});
    temporary = writer.temporary_path();
    EXPECT_EQ(temporary.parent_path(), folder);
    EXPECT_NE(temporary.filename().string().find("model.tpi.tmp-"), std::string::npos);
    std::vector<std::byte> payload(3 * kChunk, std::byte{7});
    writer.append_shard(payload);
    EXPECT_TRUE(std::filesystem::exists(temporary));
    EXPECT_FALSE(std::filesystem::exists(target));
  }
  EXPECT_FALSE(std::filesystem::exists(temporary));
  EXPECT_FALSE(std::filesystem::exists(target));
  EXPECT_TRUE(test::folder_listing(folder).empty());

  // The same when an exception unwinds the writer.
  try {
    IndexWriter writer(target);
    temporary = writer.temporary_path();
    throw InputError("interrupted");
  } catch (const InputError&) {
  }
  EXPECT_TRUE(test::folder_listing(folder).empty());
}

TEST(IndexFile, WriterRejectsBadInput) {
  const auto folder = scratch_folder("bad_input");
  expect_error<InputError>([&] { IndexWriter(folder / "a.tpi", {.chunk_bytes = 10}); },
                           {"a.tpi", "chunk size 10"});
  expect_error<InputError>([&] { IndexWriter(folder / "a.tpi", {.chunk_bytes = 1016}); },
                           {"a.tpi", "chunk size 1016"});
  expect_error<IoError>([&] { IndexWriter(folder / "missing_folder" / "a.tpi"); },
                        {"a.tpi", "cannot create"});

  IndexWriter writer(folder / "a.tpi");
  const std::vector<std::uint32_t> values{1, 2, 3};
  expect_error<InputError>([&] { writer.write_table("a/b", std::span(values)); }, {"a/b"});
  expect_error<InputError>([&] { writer.write_table("", std::span(values)); }, {"table name"});
  writer.write_table("t", std::span(values));
  expect_error<InputError>([&] { writer.write_table("t", std::span(values)); }, {"'t'", "twice"});
  TetMesh mesh;
  mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  mesh.tets = {{0, 1, 2, 4}};
  mesh.neighbours = {
      {TetMesh::no_neighbour, TetMesh::no_neighbour, TetMesh::no_neighbour, TetMesh::no_neighbour}};
  expect_error<InputError>([&] { writer.write_mesh(mesh); }, {"tet 0", "corner 3", "vertex 4"});
  mesh.tets = {{0, 1, 2, 3}};
  mesh.neighbours[0][2] = 1;
  expect_error<InputError>([&] { writer.write_mesh(mesh); }, {"tet 0", "neighbour 2", "tet 1"});
  IndexHeader header;
  header.shard_count = 3;
  expect_error<InputError>([&] { writer.commit(header); }, {"3 shards", "0 were appended"});
  header.shard_count = 0;
  header.precision = "half";
  expect_error<InputError>([&] { writer.commit(header); }, {"'half'"});
  header.precision = "double";
  EXPECT_GT(writer.commit(header), 0u);
  expect_error<InputError>([&] { writer.commit(header); }, {"already committed"});
  expect_error<InputError>([&] { writer.append_shard({}); }, {"already committed"});

  // Nothing but a header: a valid, empty index.
  const IndexReader reader(folder / "a.tpi");
  EXPECT_EQ(reader.shard_count(), 0u);
  EXPECT_EQ(reader.read_mesh().tet_count(), 0u);
  EXPECT_EQ(reader.read_table_uint32("t"), values);
  EXPECT_EQ(reader.validate(), std::vector<std::string>{});
}

// ---- the chunk codec against HDF5's own filters -----------------------------------------

/// Writes `data` (whole 8-byte words) as one chunk of little-endian words through HDF5's
/// pipeline, shuffled and compressed with LZ4 (HDF5 loads the filter plugin the HDF Group
/// distributes: an implementation independent of ours) or plain, and returns the stored chunk.
/// `lz4_blocks` is the plugin's block size, so that frames of several blocks are tried too.
std::vector<std::byte> stored_by_hdf5(const std::filesystem::path& path,
                                      const std::vector<std::byte>& data, bool compress,
                                      unsigned lz4_blocks, std::uint32_t& filter_mask) {
  const hid_t file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  const hsize_t size = data.size() / 8;
  const hid_t space = H5Screate_simple(1, &size, nullptr);
  const hid_t creation = H5Pcreate(H5P_DATASET_CREATE);
  H5Pset_chunk(creation, 1, &size);
  if (compress) {
    H5Pset_shuffle(creation);
    EXPECT_GE(H5Pset_filter(creation, detail::kLz4FilterId, H5Z_FLAG_MANDATORY, 1, &lz4_blocks), 0);
  }
  H5Pset_fletcher32(creation);
  const hid_t dataset =
      H5Dcreate2(file, "d", H5T_STD_U64LE, space, H5P_DEFAULT, creation, H5P_DEFAULT);
  EXPECT_GE(H5Dwrite(dataset, H5T_STD_U64LE, H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()), 0);
  hsize_t origin = 0, stored_bytes = 0;
  EXPECT_GE(H5Dget_chunk_storage_size(dataset, &origin, &stored_bytes), 0);
  std::vector<std::byte> stored(stored_bytes);
  EXPECT_GE(H5Dread_chunk(dataset, H5P_DEFAULT, &origin, &filter_mask, stored.data()), 0);
  H5Dclose(dataset);
  H5Pclose(creation);
  H5Sclose(space);
  H5Fclose(file);
  return stored;
}

/// Stores `encoded` as the one chunk of a dataset with /shards/data's pipeline and reads it
/// back through HDF5 (the LZ4 plugin decompresses it).
std::vector<std::byte> read_by_hdf5(const std::filesystem::path& path,
                                    const detail::EncodedChunk& encoded, std::size_t size) {
  const hid_t file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  const hsize_t words = size / 8;
  const hid_t space = H5Screate_simple(1, &words, nullptr);
  const hid_t creation = H5Pcreate(H5P_DATASET_CREATE);
  H5Pset_chunk(creation, 1, &words);
  H5Pset_shuffle(creation);
  const unsigned block = static_cast<unsigned>(size);
  H5Pset_filter(creation, detail::kLz4FilterId, H5Z_FLAG_OPTIONAL, 1, &block);
  H5Pset_fletcher32(creation);
  const hid_t dataset =
      H5Dcreate2(file, "d", H5T_STD_U64LE, space, H5P_DEFAULT, creation, H5P_DEFAULT);
  const hsize_t origin = 0;
  EXPECT_GE(H5Dwrite_chunk(dataset, H5P_DEFAULT, encoded.filter_mask, &origin, encoded.bytes.size(),
                           encoded.bytes.data()),
            0);
  H5Dclose(dataset);
  H5Pclose(creation);
  H5Sclose(space);
  H5Fclose(file);
  // Read in a new session, as a reader of an index does (in the writing session, HDF5 1.10.8
  // ran the filters that a direct write's mask skips).
  const hid_t reopened = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t read_back = H5Dopen2(reopened, "d", H5P_DEFAULT);
  std::vector<std::byte> back(size);
  EXPECT_GE(H5Dread(read_back, H5T_STD_U64LE, H5S_ALL, H5S_ALL, H5P_DEFAULT, back.data()), 0);
  H5Dclose(read_back);
  H5Fclose(reopened);
  return back;
}

/// A prefix of a chunk (a shard's last chunk, without its padding) decodes to the chunk's
/// first bytes: the empty one, one byte, a random length, and all but one byte.
void expect_prefixes_decode(const detail::EncodedChunk& encoded, const std::vector<std::byte>& data,
                            Random& random) {
  for (const std::size_t length :
       {std::size_t(0), std::size_t(1), std::size_t(random.below(data.size())), data.size() - 1}) {
    std::vector<std::byte> prefix(length, std::byte{0x5a});
    EXPECT_EQ(detail::decode_chunk(encoded.bytes, encoded.filter_mask, prefix, data.size()), "")
        << length;
    EXPECT_TRUE(std::equal(prefix.begin(), prefix.end(), data.begin())) << "prefix of " << length;
  }
  std::vector<std::byte> too_long(data.size() + 8);
  EXPECT_NE(detail::decode_chunk(encoded.bytes, encoded.filter_mask, too_long, data.size()), "");
}

/// A chunk we encoded decodes back, whole and by prefixes; HDF5 with the plugin (an
/// independent decoder) reads it as we wrote it; any single flipped byte is caught.
void expect_chunk_reads_back(const detail::EncodedChunk& encoded,
                             const std::vector<std::byte>& data,
                             const std::filesystem::path& scratch_file, Random& random) {
  std::vector<std::byte> decoded(data.size());
  EXPECT_EQ(detail::decode_chunk(encoded.bytes, encoded.filter_mask, decoded), "");
  EXPECT_EQ(decoded, data);
  EXPECT_EQ(read_by_hdf5(scratch_file, encoded, data.size()), data);
  expect_prefixes_decode(encoded, data, random);
  auto corrupted = encoded.bytes;
  corrupted[random.below(corrupted.size())] ^= std::byte{0x20};
  EXPECT_NE(detail::decode_chunk(corrupted, encoded.filter_mask, decoded), "");
}

TEST(IndexFile, ChunkCodecAgreesWithHdf5Filters) {
  // The oracle is HDF5's own pipeline with the LZ4 plugin: without it there is nothing to
  // compare with, and the test fails rather than passing vacuously.
  ASSERT_GT(H5Zfilter_avail(detail::kLz4FilterId), 0)
      << "HDF5 finds no LZ4 filter plugin: install Debian's hdf5-filter-plugin";
  const std::uint64_t seed = 4242;
  SCOPED_TRACE("seed " + std::to_string(seed));
  const auto folder = scratch_folder("codec");
  Random random(seed);
  std::size_t compressed_chunks = 0, multi_block_frames = 0;
  for (std::size_t size : {8, 16, 24, 56, 64, 72, 720, 1440, 4096, 65536, 100000}) {
    for (bool compressible : {false, true}) {
      SCOPED_TRACE("size " + std::to_string(size) + (compressible ? " compressible" : ""));
      const auto data = random_bytes(random, size, compressible);
      // Fletcher-32 only: the stored chunk is the data and HDF5's checksum.
      std::uint32_t mask = 0;
      const auto plain = stored_by_hdf5(folder / "plain.h5", data, false, 0, mask);
      ASSERT_EQ(plain.size(), size + 4);
      std::uint32_t stored_checksum = 0;
      for (int i = 0; i < 4; ++i) stored_checksum |= std::uint32_t(plain[size + i]) << (8 * i);
      EXPECT_EQ(detail::fletcher32(std::span(plain).first(size)), stored_checksum);

      // Shuffle, LZ4, Fletcher-32, as /shards/data: our decoder recovers HDF5's chunk, in one
      // block and in blocks of 1 KiB (the plugin stores a block it cannot shrink as it is).
      std::vector<std::byte> decoded(size);
      for (const unsigned blocks : {unsigned(size), 1024u}) {
        const auto compressed = stored_by_hdf5(folder / "lz4.h5", data, true, blocks, mask);
        EXPECT_EQ(detail::decode_chunk(compressed, mask, decoded), "");
        EXPECT_EQ(decoded, data);
        expect_prefixes_decode({compressed, mask}, data, random);
        multi_block_frames += blocks < size && (mask & detail::kCompressionSkipped) == 0;
      }

      // A chunk we encode decodes back, and HDF5 with the plugin reads it as we wrote it.
      detail::EncodedChunk encoded;
      detail::encode_chunk(data, encoded);
      compressed_chunks += (encoded.filter_mask & detail::kCompressionSkipped) == 0;
      expect_chunk_reads_back(encoded, data, folder / "ours.h5", random);
    }
  }
  // Both paths were taken: compressed chunks, and frames of several blocks.
  EXPECT_GE(compressed_chunks, 5u);
  EXPECT_GE(multi_block_frames, 2u);
}

TEST(IndexFile, UncompressedChunksAgreeWithHdf5Filters) {
  ASSERT_GT(H5Zfilter_avail(detail::kLz4FilterId), 0)
      << "HDF5 finds no LZ4 filter plugin: install Debian's hdf5-filter-plugin";
  const std::uint64_t seed = 4343;
  SCOPED_TRACE("seed " + std::to_string(seed));
  const auto folder = scratch_folder("codec_none");
  Random random(seed);
  // Chunks of several sizes, each with a payload of every kind of length (one byte, below and
  // above the 1 KiB block floor, one short of the chunk, the whole chunk) and zero padding.
  for (std::size_t size : {8, 64, 1024, 4096, 16384, 65536}) {
    for (std::size_t payload : {std::size_t(1), std::size_t(7), std::size_t(100), std::size_t(1023),
                                std::size_t(1025), size / 3, size - 1, size}) {
      if (payload == 0 || payload > size) continue;
      SCOPED_TRACE("chunk " + std::to_string(size) + ", payload " + std::to_string(payload));
      auto data = random_bytes(random, size, false);
      std::fill(data.begin() + std::ptrdiff_t(payload), data.end(), std::byte{0});
      detail::EncodedChunk encoded;
      detail::encode_chunk_uncompressed(data, payload, encoded);
      // The payload is stored as it is (no decompression), and the padding takes little room.
      EXPECT_NE((encoded.filter_mask & detail::kShuffleSkipped), 0u);
      // (LZ4 takes a byte per 255 zeros, and a few bytes a block.)
      EXPECT_LE(encoded.bytes.size(),
                std::max<std::size_t>(payload, (size + 15) / 16) + size / 200 + 400);
      EXPECT_NE(std::search(encoded.bytes.begin(), encoded.bytes.end(), data.begin(),
                            data.begin() + std::ptrdiff_t(payload)),
                encoded.bytes.end());
      expect_chunk_reads_back(encoded, data, folder / "none.h5", random);
    }
  }
  detail::EncodedChunk encoded;
  std::vector<std::byte> data(64, std::byte{0});
  data[40] = std::byte{1};
  expect_error<InputError>([&] { detail::encode_chunk_uncompressed(data, 32, encoded); },
                           {"byte 40", "not zero"});
  expect_error<InputError>([&] { detail::encode_chunk_uncompressed(data, 0, encoded); },
                           {"0 payload bytes"});
  expect_error<InputError>([&] { detail::encode_chunk_uncompressed(data, 65, encoded); },
                           {"65 payload bytes"});
}

TEST(IndexFile, UncompressedIndexReadsBackThroughOurReaderAndHdf5) {
  const std::uint64_t seed = 31;
  SCOPED_TRACE("seed " + std::to_string(seed));
  const auto folder = scratch_folder("index_none");
  Random random(seed);
  std::vector<std::vector<std::byte>> shards;
  for (std::size_t size : edge_sizes()) shards.push_back(random_bytes(random, size, true));
  const auto path = folder / "raw.tpi";
  const auto compressed_path = folder / "lz4.tpi";
  for (const auto compression : {ChunkCompression::none, ChunkCompression::lz4}) {
    IndexWriter writer(compression == ChunkCompression::none ? path : compressed_path,
                       {.chunk_bytes = kChunk, .compression = compression});
    for (const auto& shard : shards) writer.append_shard(shard);
    IndexHeader header;
    header.shard_count = shards.size();
    writer.commit(header);
  }
  const IndexReader reader(path);
  const IndexReader compressed(compressed_path);
  const std::string text = test::read_file(path);
  const std::vector<std::byte> file(reinterpret_cast<const std::byte*>(text.data()),
                                    reinterpret_cast<const std::byte*>(text.data()) + text.size());
  for (std::uint32_t s = 0; s < reader.shard_count(); ++s) {
    SCOPED_TRACE("shard " + std::to_string(s));
    EXPECT_EQ(reader.read_shard(s), shards[s]);
    EXPECT_EQ(reader.read_shard_through_hdf5(s), shards[s]);
    // Each chunk's payload lies in the file as it is.
    const auto chunks = reader.shard_chunks(s);
    for (std::size_t k = 0; k < chunks.size(); ++k) {
      const auto begin = shards[s].begin() + std::ptrdiff_t(k * kChunk);
      const auto end = shards[s].begin() +
                       std::ptrdiff_t(std::min<std::size_t>((k + 1) * kChunk, shards[s].size()));
      const auto stored = file.begin() + std::ptrdiff_t(chunks[k].file_offset);
      EXPECT_NE(std::search(stored, stored + std::ptrdiff_t(chunks[k].stored_bytes), begin, end),
                stored + std::ptrdiff_t(chunks[k].stored_bytes))
          << "chunk " << k;
    }
    // Compressible payloads take more room as they are, but the padding no more than a few
    // hundred bytes a chunk.
    EXPECT_GE(reader.stored_shard_size(s), compressed.stored_shard_size(s));
    EXPECT_LE(reader.stored_shard_size(s),
              shards[s].size() + reader.shard_chunks(s).size() * 400 + 1024);
  }
  EXPECT_EQ(reader.validate(), std::vector<std::string>{});
  expect_error<InputError>([] { parse_chunk_compression("zstd"); }, {"'zstd'", "lz4 or none"});
  EXPECT_EQ(parse_chunk_compression(to_string(ChunkCompression::none)), ChunkCompression::none);
}

/// HDF5's Fletcher-32 word by word, as its H5_checksum_fletcher32 states it: the reference
/// for our blockwise one.
std::uint32_t fletcher32_word_by_word(std::span<const std::byte> data) {
  std::uint32_t sum1 = 0, sum2 = 0;
  std::size_t i = 0;
  auto fold = [](std::uint32_t x) { return (x & 0xffff) + (x >> 16); };
  for (std::size_t left = data.size() / 2; left > 0;) {
    const std::size_t block = std::min<std::size_t>(left, 360);
    left -= block;
    for (std::size_t k = 0; k < block; ++k, i += 2) {
      sum1 += (std::uint32_t(data[i]) << 8) | std::uint32_t(data[i + 1]);
      sum2 += sum1;
    }
    sum1 = fold(sum1);
    sum2 = fold(sum2);
  }
  if (data.size() % 2 != 0) {
    sum1 += std::uint32_t(data[i]) << 8;
    sum2 += sum1;
    sum1 = fold(sum1);
    sum2 = fold(sum2);
  }
  sum1 = fold(sum1);
  sum2 = fold(sum2);
  return (sum2 << 16) | sum1;
}

TEST(IndexFile, Fletcher32EqualsTheWordByWordSums) {
  // Every length around the 8-word and 360-word steps, random and extreme bytes (all 0xff
  // makes the sums wrap; all zero and one odd byte test the tails).
  Random random(77);
  for (std::size_t size = 0; size < 2200; size += size < 64 ? 1 : 7) {
    for (const int fill : {-1, 0x00, 0xff}) {
      std::vector<std::byte> data(size);
      for (auto& b : data) b = std::byte(fill < 0 ? random.below(256) : std::uint64_t(fill));
      ASSERT_EQ(detail::fletcher32(data), fletcher32_word_by_word(data))
          << "size " << size << " fill " << fill;
    }
  }
  std::vector<std::byte> large(1 << 20, std::byte{0xff});
  EXPECT_EQ(detail::fletcher32(large), fletcher32_word_by_word(large));
  for (auto& b : large) b = std::byte(random.below(256));
  EXPECT_EQ(detail::fletcher32(std::span(large).subspan(3)),
            fletcher32_word_by_word(std::span(large).subspan(3)));
}

TEST(IndexFile, ChunkCodecRejectsMalformedFramesWithValidChecksums) {
  // Frames whose checksum is right but whose LZ4 framing lies: a clear problem, never a read
  // past either buffer (ASan builds check that).
  std::vector<std::byte> data(4096);
  for (std::size_t i = 0; i < data.size(); ++i) data[i] = std::byte((i / 64) & 0xff);
  detail::EncodedChunk encoded;
  detail::encode_chunk(data, encoded);
  ASSERT_EQ(encoded.filter_mask, 0u);
  const std::size_t frame_bytes = encoded.bytes.size() - detail::kChecksumBytes;
  auto with = [&](const std::function<void(std::vector<std::byte>&)>& change) {
    std::vector<std::byte> frame(encoded.bytes.begin(),
                                 encoded.bytes.begin() + std::ptrdiff_t(frame_bytes));
    change(frame);
    const std::uint32_t sum = detail::fletcher32(frame);
    for (int i = 0; i < 4; ++i) frame.push_back(std::byte((sum >> (8 * i)) & 0xff));
    std::vector<std::byte> out(data.size());
    return detail::decode_chunk(frame, 0, out);
  };
  EXPECT_EQ(with([](auto&) {}), "");
  EXPECT_NE(with([](auto& f) { f[7] = std::byte{0x01}; }).find("decodes to 4097 bytes"),
            std::string::npos);
  EXPECT_NE(
      with([](auto& f) { f[8] = f[9] = f[10] = f[11] = std::byte{0}; }).find("blocks of 0 bytes"),
      std::string::npos);
  EXPECT_NE(with([](auto& f) { f[12] = std::byte{0x7f}; }).find("runs past the frame"),
            std::string::npos);
  EXPECT_NE(with([](auto& f) { f.resize(12); }).find("ends inside a block header"),
            std::string::npos);
  EXPECT_NE(with([](auto& f) { f.resize(5); }).find("too short"), std::string::npos);
  EXPECT_NE(with([](auto& f) { f.push_back(std::byte{0}); }).find("follow the LZ4 frame"),
            std::string::npos);
  // The block's stored size one short: LZ4 runs out of input.
  EXPECT_NE(with([](auto& f) {
              const std::uint32_t shorter = static_cast<std::uint32_t>(f.size() - 16 - 1);
              for (int i = 0; i < 4; ++i)
                f[std::size_t(12 + i)] = std::byte((shorter >> (8 * (3 - i))) & 0xff);
              f.pop_back();
            }).find("cannot decompress"),
            std::string::npos);
}

// ---- broken files -------------------------------------------------------------------------

void set_root_attribute(const std::filesystem::path& path, const char* name,
                        const std::function<void(hid_t root)>& create) {
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  const hid_t root = H5Gopen2(file, "/", H5P_DEFAULT);
  if (H5Aexists(root, name) > 0) H5Adelete(root, name);
  create(root);
  H5Gclose(root);
  H5Fclose(file);
}

TEST(IndexFile, MissingForeignAndWrongVersionFilesAreRejected) {
  const auto folder = scratch_folder("rejected");
  expect_error<IoError>([&] { IndexReader reader(folder / "absent.tpi"); },
                        {"absent.tpi", "No such file"});
  test::write_file(folder / "text.tpi", "solid cube\nendsolid cube\n");
  expect_error<FormatError>([&] { IndexReader reader(folder / "text.tpi"); },
                            {"text.tpi", "not an HDF5 file"});
  test::write_file(folder / "empty.tpi", "");
  expect_error<FormatError>([&] { IndexReader reader(folder / "empty.tpi"); },
                            {"empty.tpi", "not an HDF5 file"});

  // An HDF5 file in the default (oldest) format: metadata without checksums is refused before
  // HDF5 decodes it, whatever it holds.
  const auto unchecked = folder / "unchecked.h5";
  H5Fclose(H5Fcreate(unchecked.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT));
  expect_error<FormatError>([&] { IndexReader reader(unchecked); },
                            {"unchecked.h5", "superblock version 0", "no checksums", "rebuild"});

  // An HDF5 file with checksummed metadata that is not an index.
  const auto foreign = folder / "foreign.h5";
  {
    const hid_t access = H5Pcreate(H5P_FILE_ACCESS);
    H5Pset_libver_bounds(access, H5F_LIBVER_V110, H5F_LIBVER_V110);
    H5Fclose(H5Fcreate(foreign.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, access));
    H5Pclose(access);
  }
  expect_error<FormatError>([&] { IndexReader reader(foreign); },
                            {"foreign.h5", "'format'", "not a tetrapage index"});

  const auto write_string = [](hid_t root, const char* name, const char* value) {
    const hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, std::strlen(value));
    const hid_t space = H5Screate(H5S_SCALAR);
    const hid_t attribute = H5Acreate2(root, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(attribute, type, value);
    H5Aclose(attribute);
    H5Sclose(space);
    H5Tclose(type);
  };
  const WrittenIndex written = write_sample(folder, 5);
  // A fixed-length string, as other tools write it, is read too.
  set_root_attribute(written.path, "format",
                     [&](hid_t root) { write_string(root, "format", "tetrapage-index"); });
  EXPECT_EQ(IndexReader(written.path).read_shard(4), written.shards[4]);
  set_root_attribute(written.path, "format",
                     [&](hid_t root) { write_string(root, "format", "vdb-grid"); });
  expect_error<FormatError>([&] { IndexReader reader(written.path); },
                            {"model.tpi", "'vdb-grid'", "tetrapage-index"});
  set_root_attribute(written.path, "format",
                     [&](hid_t root) { write_string(root, "format", "tetrapage-index"); });
  set_root_attribute(written.path, "version", [](hid_t root) {
    const std::uint32_t version = kIndexVersion + 1;
    const hid_t space = H5Screate(H5S_SCALAR);
    const hid_t attribute =
        H5Acreate2(root, "version", H5T_STD_U32LE, space, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(attribute, H5T_NATIVE_UINT32, &version);
    H5Aclose(attribute);
    H5Sclose(space);
  });
  expect_error<FormatError>(
      [&] { IndexReader reader(written.path); },
      {"model.tpi", "version " + std::to_string(kIndexVersion + 1), "rebuild"});
  set_root_attribute(written.path, "version",
                     [&](hid_t root) { write_string(root, "version", "1"); });
  expect_error<FormatError>([&] { IndexReader reader(written.path); },
                            {"model.tpi", "'version'", "string"});
}

/// Writes `original` back to `path`, then opens it with HDF5 and lets `edit` change it.
void edit_copy(const std::filesystem::path& path, const std::string& original,
               const std::function<void(hid_t file)>& edit) {
  test::write_file(path, original);
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  edit(file);
  H5Fclose(file);
}

// Attributes or links moved to HDF5's dense storage (a fractal heap and a B-tree: another
// writer's file) are refused before HDF5 walks that storage.
TEST(IndexFile, DenseStorageOfAttributesOrLinksIsRefused) {
  const auto folder = scratch_folder("dense");
  const WrittenIndex written = write_sample(folder, 3);
  const std::string original = test::read_file(written.path);
  const auto change = [&](const std::function<void(hid_t file)>& edit) {
    edit_copy(written.path, original, edit);
  };
  change([](hid_t file) {
    const hid_t root = H5Gopen2(file, "/", H5P_DEFAULT);
    // More than the writer keeps compact: HDF5 moves them all to dense storage.
    const hid_t space = H5Screate(H5S_SCALAR);
    for (int i = 0; i < 300; ++i) {
      const std::string name = "extra" + std::to_string(i);
      const hid_t attribute =
          H5Acreate2(root, name.c_str(), H5T_STD_U8LE, space, H5P_DEFAULT, H5P_DEFAULT);
      H5Aclose(attribute);
    }
    H5Sclose(space);
    H5Gclose(root);
  });
  expect_error<FormatError>([&] { IndexReader reader(written.path); },
                            {"model.tpi", "dense storage", "rebuild"});
  change([](hid_t file) {
    for (int i = 0; i < 5000; ++i)
      H5Lcreate_soft("/shards/data", file, ("/tables/link" + std::to_string(i)).c_str(),
                     H5P_DEFAULT, H5P_DEFAULT);
  });
  expect_error<FormatError>([&] { IndexReader reader(written.path); },
                            {"model.tpi", "'/tables'", "dense storage", "rebuild"});
  test::write_file(written.path, original);
  EXPECT_EQ(IndexReader(written.path).read_shard(1), written.shards[1]);
}

TEST(IndexFile, MissingOrMisshapedDatasetsAreRejected) {
  const auto folder = scratch_folder("datasets");
  const WrittenIndex written = write_sample(folder, 6);
  const std::string original = test::read_file(written.path);
  const auto edit = [&](const std::function<void(hid_t file)>& change) {
    edit_copy(written.path, original, change);
  };
  edit([](hid_t file) { H5Ldelete(file, "/shards/sizes", H5P_DEFAULT); });
  expect_error<FormatError>([&] { IndexReader reader(written.path); },
                            {"model.tpi", "'/shards/sizes' is missing"});
  edit([](hid_t file) { H5Ldelete(file, "/mesh", H5P_DEFAULT); });
  expect_error<FormatError>([&] { IndexReader reader(written.path); },
                            {"model.tpi", "'/mesh' is missing"});
  edit([](hid_t file) {
    H5Ldelete(file, "/mesh/tets", H5P_DEFAULT);
    const std::array<hsize_t, 2> dims{2, 3};
    const hid_t space = H5Screate_simple(2, dims.data(), nullptr);
    H5Dclose(H5Dcreate2(file, "/mesh/tets", H5T_STD_U32LE, space, H5P_DEFAULT, H5P_DEFAULT,
                        H5P_DEFAULT));
    H5Sclose(space);
  });
  expect_error<FormatError>([&] { IndexReader reader(written.path); },
                            {"model.tpi", "'/mesh/tets'", "3 columns", "expected 4"});
  // An extent past the end of /shards/data, and one off a chunk boundary.
  for (std::uint64_t bad_offset : {std::uint64_t{1} << 40, std::uint64_t{kChunk / 2}}) {
    edit([&](hid_t file) {
      const hid_t dataset = H5Dopen2(file, "/shards/offsets", H5P_DEFAULT);
      const hid_t space = H5Dget_space(dataset);
      const hsize_t start = 3, count = 1;
      H5Sselect_hyperslab(space, H5S_SELECT_SET, &start, nullptr, &count, nullptr);
      const hid_t memory = H5Screate_simple(1, &count, nullptr);
      H5Dwrite(dataset, H5T_NATIVE_UINT64, memory, space, H5P_DEFAULT, &bad_offset);
      H5Sclose(memory);
      H5Sclose(space);
      H5Dclose(dataset);
    });
    expect_error<FormatError>([&] { IndexReader reader(written.path); },
                              {"model.tpi", "shard 3", std::to_string(bad_offset)});
  }
}

TEST(IndexFile, TruncatedFilesThrowNeverCrash) {
  const auto folder = scratch_folder("truncated");
  const WrittenIndex written = write_sample(folder, 8);
  const std::string whole = test::read_file(written.path);
  const auto truncated = folder / "truncated.tpi";
  for (std::size_t length :
       {std::size_t{0}, std::size_t{7}, std::size_t{100}, std::size_t{2048}, whole.size() / 3,
        whole.size() / 2, whole.size() - 4096, whole.size() - 1}) {
    SCOPED_TRACE("truncated to " + std::to_string(length) + " of " + std::to_string(whole.size()));
    test::write_file(truncated, std::string_view(whole).substr(0, length));
    expect_error<FormatError>([&] { IndexReader reader(truncated); }, {"truncated.tpi"});
  }
}

TEST(IndexFile, FlippedByteInShardDataIsCaught) {
  const auto folder = scratch_folder("flipped");
  const WrittenIndex written = write_sample(folder, 9);
  const std::uint32_t victim = 4;  // 3 chunks + 17 bytes
  std::uint64_t offset = 0;
  for (std::uint32_t s = 0; s < victim; ++s)
    offset += (written.shards[s].size() + kChunk - 1) / kChunk * kChunk;
  // Locate the shard's second chunk through HDF5 itself, not through the reader.
  haddr_t address = HADDR_UNDEF;
  hsize_t stored = 0;
  {
    const hid_t file = H5Fopen(written.path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    const hid_t dataset = H5Dopen2(file, "/shards/data", H5P_DEFAULT);
    hsize_t coordinate = (offset + kChunk) / 8;  // in 8-byte words
    unsigned mask = 0;
    ASSERT_GE(H5Dget_chunk_info_by_coord(dataset, &coordinate, &mask, &address, &stored), 0);
    H5Dclose(dataset);
    H5Fclose(file);
  }
  ASSERT_NE(address, HADDR_UNDEF);
  {
    const IndexReader reader(written.path);
    const auto chunks = reader.shard_chunks(victim);
    ASSERT_EQ(chunks.size(), 4u);
    EXPECT_EQ(chunks[1].file_offset, address);
    EXPECT_EQ(chunks[1].stored_bytes, stored);
  }
  std::string bytes = test::read_file(written.path);
  bytes[address + stored / 2] ^= 0x01;
  test::write_file(written.path, bytes);

  const IndexReader reader(written.path);  // opening does not read shard data
  expect_error<FormatError>([&] { reader.read_shard(victim); },
                            {"model.tpi", "shard 4", "chunk 1 of 4", "Fletcher-32"});
  expect_error<FormatError>([&] { reader.read_shard_through_hdf5(victim); },
                            {"model.tpi", "shard 4"});
  for (std::uint32_t s = 0; s < reader.shard_count(); ++s) {
    if (s == victim) continue;
    EXPECT_EQ(reader.read_shard(s), written.shards[s]) << "shard " << s;
  }
  const auto problems = reader.validate();
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].find("shard 4, chunk 1 of 4"), std::string::npos) << problems[0];
}

// An index opened from its bytes in memory (HDF5's core driver) reads as the file does, and
// damaged images fail as damaged files do: truncated ones at the open, a flipped byte of a
// shard at its read.
TEST(IndexFile, AnImageInMemoryReadsAsTheFile) {
  const auto folder = scratch_folder("image");
  const WrittenIndex written = write_sample(folder, 10);
  const std::string whole = test::read_file(written.path);
  const auto image = [](std::string_view bytes) {
    return std::span<const std::byte>(reinterpret_cast<const std::byte*>(bytes.data()),
                                      bytes.size());
  };
  {
    const IndexReader reader(image(whole), "received.tpi");
    EXPECT_EQ(reader.file_bytes(), whole.size());
    EXPECT_EQ(reader.header().shard_count, written.shards.size());
    const TetMesh mesh = reader.read_mesh();
    EXPECT_EQ(mesh.vertices, written.mesh.vertices);
    EXPECT_EQ(mesh.tets, written.mesh.tets);
    EXPECT_EQ(reader.read_table_uint64("ids"), written.ids);
    for (std::uint32_t s = 0; s < reader.shard_count(); ++s) {
      EXPECT_EQ(reader.read_shard(s), written.shards[s]) << "shard " << s;
      EXPECT_EQ(reader.read_shard_through_hdf5(s), written.shards[s]) << "shard " << s;
    }
    EXPECT_EQ(reader.validate(), std::vector<std::string>{});
  }
  for (std::size_t length :
       {std::size_t{0}, std::size_t{100}, whole.size() / 2, whole.size() - 1}) {
    SCOPED_TRACE("truncated to " + std::to_string(length));
    expect_error<FormatError>(
        [&] { IndexReader reader(image(std::string_view(whole).substr(0, length)), "cut.tpi"); },
        {"cut.tpi"});
  }
  const IndexReader reader(written.path);
  const auto chunks = reader.shard_chunks(4);
  std::string damaged = whole;
  damaged[chunks[1].file_offset + chunks[1].stored_bytes / 2] ^= 0x01;
  const IndexReader opened(image(damaged), "damaged.tpi");
  expect_error<FormatError>([&] { opened.read_shard(4); },
                            {"damaged.tpi", "shard 4", "chunk 1 of 4"});
  EXPECT_EQ(opened.read_shard(3), written.shards[3]);
}

}  // namespace
}  // namespace tetrapage
