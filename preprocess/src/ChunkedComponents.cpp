#include "tetrapage/preprocess/ChunkedComponents.h"

#include <algorithm>
#include <string>

#include "SpillPath.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/PositionBits.h"

namespace tetrapage {
namespace {

// The most buckets open at once, and the split of a bucket that outgrew its bytes.
constexpr std::uint64_t kMostBuckets = 256;
constexpr std::uint64_t kSplitBuckets = 16;
constexpr unsigned kMostSplits = 3;

template <class Record>
std::uint64_t hash_of(const Record& r, unsigned depth) {
  return mix_bits(mix_bits(mix_bits(r.bits[0] ^ (std::uint64_t(r.part) << 32) ^ depth) + r.bits[1]) + r.bits[2]);
}

template <class Record>
bool same_place(const Record& a, const Record& b) {
  return a.bits[0] == b.bits[0] && a.bits[1] == b.bits[1] && a.bits[2] == b.bits[2] &&
         a.part == b.part;
}

template <class Record>
bool place_before(const Record& a, const Record& b) {
  for (int k = 0; k < 3; ++k)
    if (a.bits[k] != b.bits[k]) return a.bits[k] < b.bits[k];
  return a.part < b.part;
}

}  // namespace

ChunkedComponents::ChunkedComponents(const std::filesystem::path& spill_folder,
                                     const std::string& name, std::uint64_t expected_positions,
                                     std::uint64_t bucket_bytes)
    : spill_folder_(spill_folder),
      name_(name),
      bucket_bytes_(std::max<std::uint64_t>(bucket_bytes, 1)),
      labels_(spill_path(spill_folder, name + "-labels")) {
  const std::uint64_t bytes = expected_positions * sizeof(PositionRecord);
  const std::uint64_t count = std::clamp<std::uint64_t>(bytes / bucket_bytes_ + 1, 1, kMostBuckets);
  buckets_.reserve(count);
  for (std::uint64_t b = 0; b < count; ++b)
    buckets_.emplace_back(spill_path(spill_folder_, name_ + "-positions-" + std::to_string(b)));
}

std::uint64_t ChunkedComponents::label_bytes() const {
  // The parents, and a component number each once united.
  return sets_.bytes() + sets_.size() * sizeof(std::uint32_t);
}

void ChunkedComponents::add_chunk(TriangleSoup& chunk, std::uint64_t first_triangle) {
  SurfaceComponents found = find_surface_components(chunk);
  const auto first_label = std::uint32_t(sets_.size());
  if (sets_.size() + found.components.size() >= 0xfffffffeu)
    throw InputError("the file holds more than 2^32 - 2 pieces of connected components");
  std::vector<LabelRecord> records(found.components.size());
  for (std::size_t c = 0; c < found.components.size(); ++c) {
    found.components[c].first_triangle += first_triangle;
    records[c] = {found.components[c], found.parities[c]};
    sets_.add();
  }
  labels_.append(std::span<const LabelRecord>(records));
  note_positions(chunk, found.component_of, first_label);
  for (std::size_t t = 0; t < chunk.triangle_count(); ++t)
    chunk.part_of[t] = first_label + found.component_of[t];
}

// Each distinct (position, part) of the chunk once: a position meets one label in a chunk
// (the chunk's components are whole within it). A vertex entry is noted once per part (an
// indexed chunk's vertices serve about six triangles), then equal positions of distinct
// entries (an STL's) are sorted out.
void ChunkedComponents::note_positions(const TriangleSoup& chunk,
                                       const std::vector<std::uint32_t>& component_of,
                                       std::uint32_t first_label) {
  constexpr std::uint32_t kNone = 0xffffffffu;
  std::vector<PositionRecord>& records = chunk_positions_;
  records.clear();
  noted_part_.assign(chunk.vertices.size(), kNone);
  for (std::size_t t = 0; t < chunk.triangle_count(); ++t) {
    const std::uint32_t part = chunk.part_of.empty() ? 0 : chunk.part_of[t];
    for (const std::uint32_t v : chunk.triangles[t]) {
      if (noted_part_[v] == part) continue;
      noted_part_[v] = part;
      const Vec3& p = chunk.vertices[v];
      records.push_back({{coordinate_bits(p[0]), coordinate_bits(p[1]), coordinate_bits(p[2])}, part,
                         first_label + component_of[t]});
    }
  }
  std::sort(records.begin(), records.end(), place_before<PositionRecord>);
  records.erase(std::unique(records.begin(), records.end(), same_place<PositionRecord>),
                records.end());
  // Grouped by bucket (a counting sort): one write per bucket and chunk.
  const std::size_t count = buckets_.size();
  bucket_of_.resize(records.size());
  std::vector<std::size_t> first(count + 1, 0);
  for (std::size_t i = 0; i < records.size(); ++i) {
    bucket_of_[i] = std::uint32_t(hash_of(records[i], 0) % count);
    ++first[bucket_of_[i] + 1];
  }
  for (std::size_t b = 0; b < count; ++b) first[b + 1] += first[b];
  grouped_.resize(records.size());
  std::vector<std::size_t> next(first.begin(), first.end() - 1);
  for (std::size_t i = 0; i < records.size(); ++i) grouped_[next[bucket_of_[i]]++] = records[i];
  for (std::size_t b = 0; b < count; ++b)
    buckets_[b].append(std::span<const PositionRecord>(grouped_.data() + first[b], first[b + 1] - first[b]));
}

void ChunkedComponents::unite_bucket(RecordSpill<PositionRecord>& bucket, unsigned depth) {
  if (bucket.size() * sizeof(PositionRecord) > bucket_bytes_ && depth < kMostSplits) {
    std::vector<RecordSpill<PositionRecord>> parts;
    for (std::uint64_t b = 0; b < kSplitBuckets; ++b)
      parts.emplace_back(spill_path(spill_folder_, name_ + "-positions-" + std::to_string(depth + 1) +
                                                       "-" + std::to_string(b)));
    bucket.for_each_block(1 << 14, [&](std::span<const PositionRecord> block) {
      for (const PositionRecord& r : block)
        parts[hash_of(r, depth + 1) % kSplitBuckets].append(std::span<const PositionRecord>(&r, 1));
    });
    bucket.clear();
    for (RecordSpill<PositionRecord>& part : parts) unite_bucket(part, depth + 1);
    return;
  }
  std::vector<PositionRecord> records = bucket.read_all();
  bucket.clear();
  std::sort(records.begin(), records.end(), place_before<PositionRecord>);
  for (std::size_t i = 1; i < records.size(); ++i)
    if (same_place(records[i - 1], records[i])) sets_.unite(records[i - 1].label, records[i].label);
}

ChunkedComponents::United ChunkedComponents::unite(std::uint64_t most_components,
                                                   const std::string& refusal) {
  for (RecordSpill<PositionRecord>& bucket : buckets_) unite_bucket(bucket, 0);
  std::vector<RecordSpill<PositionRecord>>().swap(buckets_);
  std::vector<PositionRecord>().swap(chunk_positions_);
  std::vector<PositionRecord>().swap(grouped_);
  std::vector<std::uint32_t>().swap(bucket_of_);
  std::vector<std::uint32_t>().swap(noted_part_);

  // Labels ascend with their first triangles, and a root is its set's least label: the first
  // label met of each set numbers its component, in the order of first triangles; the labels'
  // records are read back in that order.
  constexpr std::uint32_t kNone = 0xffffffffu;
  United united;
  united.component_of_label.assign(sets_.size(), kNone);
  std::vector<EdgeParity> parity;
  std::uint32_t label = 0;
  labels_.for_each_block(1 << 12, [&](std::span<const LabelRecord> block) {
    for (const LabelRecord& record : block) {
      const std::uint32_t root = sets_.find(label);
      std::uint32_t& component = united.component_of_label[root];
      if (component == kNone) {
        if (united.components.size() >= most_components) throw InputError(refusal);
        component = std::uint32_t(united.components.size());
        united.components.push_back(record.component);
        parity.push_back(record.parity);
      } else {
        SurfaceComponent& into = united.components[component];
        into.triangles += record.component.triangles;
        into.bounds.extend(record.component.bounds);
        parity[component].merge(record.parity);
      }
      united.component_of_label[label++] = component;
    }
  });
  for (std::size_t c = 0; c < parity.size(); ++c) united.components[c].closed = parity[c].closed();
  sets_ = UnionFind();
  labels_.clear();
  return united;
}

}  // namespace tetrapage
