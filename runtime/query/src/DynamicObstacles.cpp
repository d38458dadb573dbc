#include "tetrapage/runtime/query/DynamicObstacles.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "PlacedObject.h"
#include "tetrapage/formats/base/Error.h"

namespace tetrapage {
namespace {

// A name the overlay file can hold on a line of its own and read back.
void require_savable_name(const std::string& name, DynamicPartId id) {
  if (name.find('\n') != std::string::npos)
    throw InputError("dynamic part " + std::to_string(id) + ": a name may not hold a line break");
  if (name.size() > kMaxObstacleNameBytes)
    throw InputError("dynamic part " + std::to_string(id) + ": its name has " +
                     std::to_string(name.size()) + " bytes, more than " +
                     std::to_string(kMaxObstacleNameBytes));
}

}  // namespace

DynamicObstacles::DynamicObstacles(std::shared_ptr<const CollisionIndex> index, double cell_size)
    : index_(std::move(index)) {
  if (!index_) throw InputError("dynamic obstacles need an index");
  if (!(cell_size >= 0) || !std::isfinite(cell_size))
    throw InputError("dynamic obstacles: the cell size must be finite and >= 0, not " +
                     std::to_string(cell_size));
  const BoundingBox& bounds = index_->mesh_bounds();
  const double side = std::max(
      {bounds.hi[0] - bounds.lo[0], bounds.hi[1] - bounds.lo[1], bounds.hi[2] - bounds.lo[2]});
  cell_size_ = cell_size > 0 ? cell_size : side / 64;
  if (!(cell_size_ > 0)) cell_size_ = 1;  // a flat or empty mesh box
  // At most 2^20 cells an axis: a cell's key packs 21 bits an axis.
  cell_size_ = std::max(cell_size_, side * 0x1p-20);
  hidden_.assign(index_->parts().count(), 0);
}

DynamicObstacles::~DynamicObstacles() = default;
DynamicObstacles::DynamicObstacles(DynamicObstacles&&) noexcept = default;
DynamicObstacles& DynamicObstacles::operator=(DynamicObstacles&&) noexcept = default;

std::uint64_t DynamicObstacles::CellRange::count() const {
  std::uint64_t n = 1;
  for (int a = 0; a < 3; ++a) n *= std::uint64_t(hi[a] - lo[a] + 1);
  return n;
}

DynamicObstacles::CellKey DynamicObstacles::key(std::int64_t x, std::int64_t y, std::int64_t z) {
  // Cells are clamped to the mesh box, at most 2^20 an axis: 21 bits an axis.
  constexpr std::int64_t kMask = (std::int64_t(1) << 21) - 1;
  return (CellKey(x & kMask) << 42) | (CellKey(y & kMask) << 21) | CellKey(z & kMask);
}

std::array<std::int64_t, 3> DynamicObstacles::coordinates(CellKey key) {
  constexpr CellKey kMask = (CellKey(1) << 21) - 1;
  return {std::int64_t((key >> 42) & kMask), std::int64_t((key >> 21) & kMask),
          std::int64_t(key & kMask)};
}

DynamicObstacles::CellRange DynamicObstacles::cells_of(const geometry::Box& box) const {
  // Cells counted from the mesh box's low corner, clamped to it (a part outside it shares the
  // border cells). The map from a coordinate to its cell is monotone, rounding included, and
  // parts and queries use this one function: two boxes that meet share a cell.
  const BoundingBox& bounds = index_->mesh_bounds();
  CellRange range;
  for (int a = 0; a < 3; ++a) {
    const double last = std::floor((bounds.hi[a] - bounds.lo[a]) / cell_size_);
    auto cell = [&](double x) {
      return std::int64_t(std::clamp(std::floor((x - bounds.lo[a]) / cell_size_), 0.0, last));
    };
    range.lo[a] = cell(box.lo[a]);
    range.hi[a] = cell(box.hi[a]);
  }
  return range;
}

geometry::Box DynamicObstacles::placed_box(const ObjectModel& model, const Pose& pose,
                                           DynamicPartId id) const {
  PlacedObject placed(model);
  try {
    placed.place(pose);
  } catch (const InputError& e) {
    throw InputError("dynamic part " + std::to_string(id) + ": " + e.what());
  }
  return placed.world_box();
}

void DynamicObstacles::add_to_grid(std::uint32_t slot) {
  const Part& part = parts_[slot];
  const CellRange range = cells_of(part.world_box);
  if (range.count() > kMaxCellsPerPart) {
    wide_.push_back(part.id);
    return;
  }
  for (std::int64_t x = range.lo[0]; x <= range.hi[0]; ++x)
    for (std::int64_t y = range.lo[1]; y <= range.hi[1]; ++y)
      for (std::int64_t z = range.lo[2]; z <= range.hi[2]; ++z)
        grid_[key(x, y, z)].push_back(part.id);
}

void DynamicObstacles::remove_from_grid(std::uint32_t slot) {
  const Part& part = parts_[slot];
  const CellRange range = cells_of(part.world_box);
  auto erase_from = [&](std::vector<DynamicPartId>& ids) {
    const auto it = std::find(ids.begin(), ids.end(), part.id);
    if (it != ids.end()) *it = ids.back(), ids.pop_back();
  };
  if (range.count() > kMaxCellsPerPart) return erase_from(wide_);
  for (std::int64_t x = range.lo[0]; x <= range.hi[0]; ++x)
    for (std::int64_t y = range.lo[1]; y <= range.hi[1]; ++y)
      for (std::int64_t z = range.lo[2]; z <= range.hi[2]; ++z) {
        const auto cell = grid_.find(key(x, y, z));
        if (cell == grid_.end()) continue;
        erase_from(cell->second);
        if (cell->second.empty()) grid_.erase(cell);  // the grid holds occupied cells only
      }
}

std::uint32_t DynamicObstacles::slot_of(DynamicPartId id, const char* action) const {
  const auto it = slot_.find(id);
  if (it == slot_.end())
    throw InputError(std::string("cannot ") + action + " dynamic part " + std::to_string(id) +
                     ": the overlay holds no such part");
  return it->second;
}

DynamicPartId DynamicObstacles::insert(TriangleSoup mesh, const Pose& pose, std::string name) {
  return insert(std::make_shared<const ObjectModel>(std::move(mesh)), pose, std::move(name));
}

DynamicPartId DynamicObstacles::insert(std::shared_ptr<const ObjectModel> model, const Pose& pose,
                                       std::string name) {
  if (!model) throw InputError("dynamic part " + std::to_string(next_id_) + " has no model");
  if (next_id_ == 0xffffffffu) throw InputError("dynamic obstacles: every part id was used");
  require_savable_name(name, next_id_);
  const DynamicPartId id = next_id_;
  const geometry::Box box = placed_box(*model, pose, id);
  ++next_id_;
  const auto slot = std::uint32_t(parts_.size());
  parts_.push_back(Part{id, std::move(name), std::move(model), pose, box});
  slot_.emplace(id, slot);
  add_to_grid(slot);
  ++version_;
  return id;
}

void DynamicObstacles::move(DynamicPartId id, const Pose& pose) {
  const std::uint32_t slot = slot_of(id, "move");
  Part& part = parts_[slot];
  const geometry::Box box = placed_box(*part.model, pose, id);
  // Most moves are small: a part whose cells do not change stays where it is in the grid.
  const CellRange before = cells_of(part.world_box), after = cells_of(box);
  const bool same_cells = before.lo == after.lo && before.hi == after.hi;
  if (!same_cells) remove_from_grid(slot);
  part.pose = pose;
  part.world_box = box;
  if (!same_cells) add_to_grid(slot);
  ++version_;
}

void DynamicObstacles::remove(DynamicPartId id) {
  const std::uint32_t slot = slot_of(id, "remove");
  remove_from_grid(slot);
  slot_.erase(id);
  if (slot + 1 != parts_.size()) {
    parts_[slot] = std::move(parts_.back());
    slot_[parts_[slot].id] = slot;
  }
  parts_.pop_back();
  ++version_;
}

const DynamicObstacles::Part* DynamicObstacles::find(DynamicPartId id) const {
  const auto it = slot_.find(id);
  return it == slot_.end() ? nullptr : &parts_[it->second];
}

void DynamicObstacles::hide_part(std::uint32_t part) {
  if (part >= hidden_.size())
    throw InputError("cannot hide part " + std::to_string(part) + ": the index lists " +
                     std::to_string(hidden_.size()) + " parts");
  if (!hidden_[part]) hidden_[part] = 1, ++hidden_count_;
  ++version_;
}

void DynamicObstacles::show_part(std::uint32_t part) {
  if (part >= hidden_.size())
    throw InputError("cannot show part " + std::to_string(part) + ": the index lists " +
                     std::to_string(hidden_.size()) + " parts");
  if (hidden_[part]) hidden_[part] = 0, --hidden_count_;
  ++shows_;
  ++version_;
}

std::vector<std::uint32_t> DynamicObstacles::hidden_parts() const {
  std::vector<std::uint32_t> parts;
  for (std::uint32_t p = 0; p < hidden_.size(); ++p)
    if (hidden_[p]) parts.push_back(p);
  return parts;
}

}  // namespace tetrapage
