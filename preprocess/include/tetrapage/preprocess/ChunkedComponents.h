#pragma once
/// @file ChunkedComponents.h
/// The surfaces' connected components of a file read in chunks (read_mesh_in_chunks), found
/// without holding the file: each chunk's components get labels, and the labels that share a
/// position within a part are united afterwards through buckets of positions on disk, one
/// bucket in memory at a time. The result is find_surface_components' for the whole file: the
/// same components, numbered in the order of their first triangles, with the same members.

#include <array>
#include <cstdint>
#include <filesystem>
#include <vector>

#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/formats/mesh/EdgeParity.h"
#include "tetrapage/formats/mesh/SurfaceComponents.h"
#include "tetrapage/formats/mesh/UnionFind.h"
#include "tetrapage/preprocess/RecordSpill.h"

namespace tetrapage {

class ChunkedComponents {
 public:
  /// Buckets in `spill_folder`, their names starting with `name` (files found at once must
  /// differ), as many as `expected_positions` (the file's distinct vertex positions, about)
  /// need for each to hold about `bucket_bytes`.
  /// @throw IoError when a bucket cannot be created.
  ChunkedComponents(const std::filesystem::path& spill_folder, const std::string& name,
                    std::uint64_t expected_positions, std::uint64_t bucket_bytes);

  /// Finds the components of `chunk`, whose part_of holds the file's parts and whose first
  /// triangle is the file's `first_triangle`, and replaces part_of by their labels (ascending
  /// in the order of their first triangles over the whole file).
  /// @throw IoError when a bucket cannot be written.
  void add_chunk(TriangleSoup& chunk, std::uint64_t first_triangle);

  std::uint64_t label_count() const { return sets_.size(); }
  /// The bytes the labels take in memory: a parent each while they are found, and a component
  /// each once united (a chunk of a file whose triangles come in no spatial order holds many
  /// pieces of one component; their records wait on disk).
  std::uint64_t label_bytes() const;

  struct United {
    std::vector<SurfaceComponent> components;  ///< numbered by first triangle
    std::vector<std::uint32_t> component_of_label;
  };
  /// Unites the labels whose triangles share a position within a part and numbers the
  /// components; the buckets are emptied.
  /// @throw InputError `refusal` when there are more than `most_components`; IoError when a
  /// bucket cannot be read back.
  United unite(std::uint64_t most_components, const std::string& refusal);

 private:
  // A distinct (position, part) of a chunk and the label of its triangles there.
  struct PositionRecord {
    std::array<std::uint64_t, 3> bits;  // the coordinates' bits, -0.0 read as 0.0
    std::uint32_t part, label;
  };
  void note_positions(const TriangleSoup& chunk, const std::vector<std::uint32_t>& component_of,
                      std::uint32_t first_label);
  // Unites the labels of one bucket's equal positions; a bucket larger than bucket_bytes_ is
  // split by another hash first.
  void unite_bucket(RecordSpill<PositionRecord>& bucket, unsigned depth);

  // A label's piece of a component, as the chunk found it.
  struct LabelRecord {
    SurfaceComponent component;
    EdgeParity parity;
  };

  std::filesystem::path spill_folder_;
  std::string name_;
  std::uint64_t bucket_bytes_;
  std::vector<RecordSpill<PositionRecord>> buckets_;
  RecordSpill<LabelRecord> labels_;
  UnionFind sets_;  // of the labels
  // A chunk's positions, grouped by bucket, and what sorts them out (kept across chunks).
  std::vector<PositionRecord> chunk_positions_, grouped_;
  std::vector<std::uint32_t> bucket_of_, noted_part_;
};

}  // namespace tetrapage
