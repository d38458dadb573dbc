#include "tetrapage/runtime/paging/CollisionIndex.h"
#include "tetrapage/formats/index/IndexSchema.h"

#include "tetrapage/runtime/paging/BoxSearch.h"

#include "tetrapage/formats/base/Error.h"

#include <algorithm>
#include <cmath>
#include <mutex>

namespace tetrapage {

namespace schema = index_schema;

CollisionIndex::CollisionIndex(const std::filesystem::path& path, CollisionIndexOptions options)
    : reader_(path), options_(options) {
  if (options_.memory_budget_bytes == 0) throw InputError("the shard memory budget must be positive");
  mesh_ = reader_.read_mesh();  // checks every vertex and neighbour index
  for (const auto& v : mesh_.vertices) mesh_bounds_.extend(v);
  tet_filter_ = TetBoxFilter(mesh_);
  tet_shard_ = reader_.read_table_uint32(schema::table::tet_shard);
  const std::string where = path.string() + ": ";
  if (tet_shard_.size() != mesh_.tet_count())
    throw FormatError(where + schema::table_path(schema::table::tet_shard) + " has " +
                      std::to_string(tet_shard_.size()) + " entries for " +
                      std::to_string(mesh_.tet_count()) + " tets");
  if (mesh_.tet_count() == 0) throw FormatError(where + "the coarse mesh has no tet");
  const std::uint32_t shards = reader_.shard_count();
  for (std::size_t t = 0; t < tet_shard_.size(); ++t)
    if (tet_shard_[t] != TetMesh::no_neighbour && tet_shard_[t] >= shards)
      throw FormatError(where + schema::table_path(schema::table::tet_shard) + " names shard " +
                        std::to_string(tet_shard_[t]) + " for tet " + std::to_string(t) +
                        ", but there are " + std::to_string(shards) + " shards");
  const auto bounds = reader_.read_table_double(schema::table::shard_bounds);
  if (bounds.size() != 6 * std::size_t(shards))
    throw FormatError(where + schema::table_path(schema::table::shard_bounds) + " has " +
                      std::to_string(bounds.size()) + " values for " + std::to_string(shards) +
                      " shards (6 each)");
  shard_bounds_.resize(shards);
  for (std::uint32_t s = 0; s < shards; ++s) {
    geometry::Box stored;
    for (int a = 0; a < 3; ++a) {
      stored.lo[a] = bounds[6 * s + a];
      stored.hi[a] = bounds[6 * s + 3 + a];
    }
    shard_bounds_[s] = geometry::FloatBox::enclosing(stored);
  }
  shard_bytes_.resize(shards);
  for (std::uint32_t s = 0; s < shards; ++s) {
    // The decoded shard holds its payload's arrays plus the object itself: announce an upper
    // bound so that the cache reserves enough before loading.
    shard_bytes_[s] = reader_.shard_size(s) + 4096;
    total_shard_bytes_ += shard_bytes_[s];
  }
  check_budget_fits_shards();
  read_components(where);
  const std::uint32_t listed_parts =
      component_part_.empty() ? 0 : *std::max_element(component_part_.begin(), component_part_.end()) + 1;
  parts_ = IndexParts::read(reader_, listed_parts);
  stores_input_coordinates_ = header().precision != "float";
  read_interiors(where);
  ShardCacheOptions cache_options;
  cache_options.prefetch_threads = options_.prefetch ? std::max<std::size_t>(1, options_.prefetch_threads) : 0;
  cache_options.spin_before_sleep = options_.spin_before_sleep;
  // The chunk reads hold their lock for a few microseconds: the reader polls for at most 100.
  reader_.set_spin_before_sleep(std::min(options_.spin_before_sleep, std::chrono::microseconds(100)));
  if (options_.shard_arena) {
    const std::uint64_t most = std::min(options_.memory_budget_bytes, total_shard_bytes_);
    // Address space for twice the budget (free blocks of one size class cannot serve another);
    // resident, about the budget: populated ahead only within it, and freed blocks give their
    // pages back past it.
    arena_ = std::make_unique<ShardArena>(std::size_t(2 * most), std::size_t(8) << 20,
                                          std::pmr::new_delete_resource(), std::size_t(most));
  }
  const IndexReader* reader = &reader_;
  std::pmr::memory_resource* memory = arena_.get();
  cache_ = std::make_unique<ShardCache<Shard>>(
      options_.memory_budget_bytes,
      [reader, memory](std::uint32_t shard) {
        // One payload buffer per loading thread: the decoded shard keeps copies of its arrays.
        // The checksums guard the payload's boxes on disk: a page-in checks its structure only.
        thread_local std::vector<std::byte> payload;
        reader->read_shard(shard, payload);
        Shard decoded_shard =
            Shard::decode(payload, "shard " + std::to_string(shard), DecodeChecks::structure, memory);
        // The shard object and its count in the arena too: the arena then holds all a
        // resident shard is counted for.
        auto decoded = memory != nullptr ? std::allocate_shared<const Shard>(
                                               std::pmr::polymorphic_allocator<Shard>(memory), std::move(decoded_shard))
                                         : std::make_shared<const Shard>(std::move(decoded_shard));
        if (payload.capacity() > (std::size_t(1) << 20)) std::vector<std::byte>().swap(payload);  // a rare large shard
        return decoded;
      },
      shards, [this](std::uint32_t shard) { return shard_bytes_[shard]; }, cache_options);
}

CollisionIndex::~CollisionIndex() = default;

// A budget that cannot hold the largest shard would fail at the first query that needs it:
// say so at open, naming the budget and the shard.
void CollisionIndex::check_budget_fits_shards() const {
  const auto largest = std::max_element(shard_bytes_.begin(), shard_bytes_.end());
  if (largest == shard_bytes_.end() || *largest <= options_.memory_budget_bytes) return;
  throw InputError(path().string() + ": the memory budget of " + std::to_string(options_.memory_budget_bytes) +
                   " bytes is smaller than shard " + std::to_string(largest - shard_bytes_.begin()) + ", which needs " +
                   std::to_string(*largest) + " bytes decoded");
}

void CollisionIndex::read_components(const std::string& where) {
  component_part_ = reader_.read_table_uint32(schema::table::component_part);
  component_closed_ = reader_.read_table_uint8(schema::table::component_closed);
  const auto bounds = reader_.read_table_double(schema::table::component_bounds);
  const std::size_t count = component_part_.size();
  if (component_closed_.size() != count || bounds.size() != 6 * count)
    throw FormatError(where + schema::table_path(schema::table::component_closed) +
                      " and component_bounds hold " + std::to_string(component_closed_.size()) +
                      " and " + std::to_string(bounds.size()) + " values for " +
                      std::to_string(count) + " components (1 and 6 each)");
  component_bounds_.resize(count);
  for (std::size_t c = 0; c < count; ++c) {
    geometry::Box& box = component_bounds_[c];
    for (int a = 0; a < 3; ++a) box.lo[a] = bounds[6 * c + a], box.hi[a] = bounds[6 * c + 3 + a];
    if (!(box.lo[0] <= box.hi[0] && box.lo[1] <= box.hi[1] && box.lo[2] <= box.hi[2]))
      throw FormatError(where + schema::table_path(schema::table::component_bounds) +
                        " holds an empty or non-finite box for component " + std::to_string(c));
    if (component_part_[c] != kNoPart)
      for (int a = 0; a < 3; ++a)
        shortest_component_extent_[a] = std::min(shortest_component_extent_[a], box.hi[a] - box.lo[a]);
  }
}

void CollisionIndex::read_interiors(const std::string& where) {
  const auto names = reader_.table_names();
  const auto has = [&](std::string_view name) { return std::find(names.begin(), names.end(), name) != names.end(); };
  if (!has(schema::table::interior_offsets)) return;  // written without interiors: surfaces only
  const std::size_t tets = mesh_.tet_count();
  const auto points = reader_.read_table_double(schema::table::reference_points);
  auto offsets = reader_.read_table_uint64(schema::table::interior_offsets);
  interior_components_ = reader_.read_table_uint32(schema::table::interior_components);
  if (points.size() != 3 * tets)
    throw FormatError(where + schema::table_path(schema::table::reference_points) + " has " +
                      std::to_string(points.size()) + " values for " + std::to_string(tets) +
                      " tets (3 each)");
  if (offsets.size() != tets + 1 || offsets.front() != 0 || offsets.back() != interior_components_.size())
    throw FormatError(where + schema::table_path(schema::table::interior_offsets) +
                      " does not delimit " +
                      schema::table_path(schema::table::interior_components) + " for " +
                      std::to_string(tets) + " tets");
  for (std::size_t t = 0; t < tets; ++t) {
    if (offsets[t + 1] < offsets[t])
      throw FormatError(where + schema::table_path(schema::table::interior_offsets) +
                        " decreases at tet " + std::to_string(t));
    for (std::uint64_t i = offsets[t]; i < offsets[t + 1]; ++i) {
      const std::uint32_t component = interior_components_[i];
      const bool undecided = component == kInteriorUndecided && offsets[t + 1] - offsets[t] == 1;
      if (!undecided && !component_closed(component))
        throw FormatError(where + schema::table_path(schema::table::interior_components) +
                          " names component " + std::to_string(component) + " for tet " +
                          std::to_string(t) + ", which is not a closed component");
    }
  }
  reference_points_.resize(tets);
  for (std::size_t t = 0; t < tets; ++t) {
    reference_points_[t] = {points[3 * t], points[3 * t + 1], points[3 * t + 2]};
    // A NaN point is stored for an undecided tet only; any other must lie in its tet.
    const bool finite = std::isfinite(points[3 * t]) && std::isfinite(points[3 * t + 1]) && std::isfinite(points[3 * t + 2]);
    if (!finite && !(offsets[t + 1] - offsets[t] == 1 && interior_components_[offsets[t]] == kInteriorUndecided))
      throw FormatError(where + schema::table_path(schema::table::reference_points) +
                        " holds a non-finite point for tet " + std::to_string(t));
  }
  interior_offsets_ = std::move(offsets);
}

const std::vector<std::uint64_t>& CollisionIndex::shard_id_ranges() const {
  // Read on first use: only id lookups need them, and they are 16 bytes a shard.
  std::call_once(shard_id_ranges_read_, [this] {
    if (!reader_.has_table(schema::table::shard_id_ranges)) return;  // an index from before the table
    std::vector<std::uint64_t> ranges = reader_.read_table_uint64(schema::table::shard_id_ranges);
    if (ranges.size() != 2 * std::size_t(shard_count()))
      throw FormatError(reader_.path().string() + ": " + schema::table_path(schema::table::shard_id_ranges) +
                        " has " + std::to_string(ranges.size()) + " values for " +
                        std::to_string(shard_count()) + " shards (2 each)");
    shard_id_ranges_ = std::move(ranges);
  });
  return shard_id_ranges_;
}

std::optional<CollisionIndex::StoredTriangle> CollisionIndex::stored_triangle(std::uint64_t id) const {
  if (id >= header().input_triangles) return std::nullopt;
  const std::vector<std::uint64_t>& ranges = shard_id_ranges();
  for (std::uint32_t shard = 0; shard < shard_count(); ++shard) {
    if (!ranges.empty() && (id < ranges[2 * shard] || id > ranges[2 * shard + 1]))
      continue;
    const auto pin = cache_->acquire(shard);
    for (std::uint32_t local = 0; local < pin->triangle_count(); ++local)
      if (pin->triangle_id(local) == id) return StoredTriangle{pin->triangle(local), shard, pin->component_id(local)};
  }
  return std::nullopt;
}

void CollisionIndex::preload(const std::function<void(std::uint32_t)>& progress) const {
  if (total_shard_bytes_ > options_.memory_budget_bytes)
    throw InputError(path().string() + ": its " + std::to_string(total_shard_bytes_) +
                     " bytes of shards do not fit a budget of " + std::to_string(options_.memory_budget_bytes) +
                     " bytes, so they cannot all be preloaded");
  for (std::uint32_t shard = 0; shard < shard_count(); ++shard) {
    (void)cache_->acquire(shard);
    if (progress) progress(shard + 1);
  }
  const std::uint64_t resident = cache_->counters().resident_shards;
  if (resident != shard_count())
    throw InputError(path().string() + ": " + std::to_string(resident) + " of " + std::to_string(shard_count()) +
                     " shards stayed resident after preloading");
}

}  // namespace tetrapage
