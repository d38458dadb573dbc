#pragma once
/// @file DynamicObstacles.h
/// Obstacles that change without preprocessing (the study's section 5.5): an overlay on one
/// index of dynamic parts, each a rigid mesh at a pose, inserted, moved and removed at run
/// time, and a mask of the index's own parts hidden from the answers (a part being grasped, a
/// door opened). A FlyingObject given the overlay (FlyingObject::set_obstacles) answers as if
/// the index held its visible parts plus the dynamic parts placed by apply_pose (the canonical
/// placement): contacts, containment both ways, first_hit and all_contacts, every shape,
/// motion and accuracy.
///
/// Dynamic parts live in a uniform hash grid over their world boxes (cells of cell_size()):
/// insert, move and remove cost the cells a part's box covers, a box query the cells it covers
/// plus the parts found; a part wider than kMaxCellsPerPart cells sits in a short list that
/// every query scans. The grid covers the index's mesh box: parts outside it are answered
/// too, but share its border cells (slower when many stand there).
///
/// Limits: a swept step (Motion::swept) sweeps the object, not the parts (each is taken at
/// its current pose). FlyingObject::distance decides touching with the overlay but measures
/// the distance to the index's parts only, hidden ones included. Where a hidden closed part
/// encloses a visible one that holds the object, the index's interior walk may name the hidden
/// one only, and the object is then reported free.
///
/// Threading: changes (insert, move, remove, hide, show, load) from one thread, between the
/// steps of the FlyingObjects that hold the overlay; steps of any number of FlyingObjects on
/// any threads may read it at once while nothing changes it (every read is const and keeps no
/// scratch). Each change bumps version(): a FlyingObject that sees a new version drops its
/// free box when a part's box meets it or a part was shown, so a part inserted into the free
/// box is seen on the very next step (and a part moving far away costs the free box nothing).

#include <algorithm>
#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/runtime/geometry/Box.h"
#include "tetrapage/runtime/paging/CollisionIndex.h"
#include "tetrapage/runtime/query/ObjectModel.h"

namespace tetrapage {

/// A dynamic part's id: stable, never reused by its overlay; 0 is no part.
using DynamicPartId = std::uint32_t;
inline constexpr DynamicPartId kNoDynamicPart = 0;
/// The longest name a dynamic part may have, in bytes (an overlay file's line is bounded).
inline constexpr std::size_t kMaxObstacleNameBytes = 4096;

class DynamicObstacles {
 public:
  /// One dynamic part, as a query reads it.
  struct Part {
    DynamicPartId id = kNoDynamicPart;
    std::string name;
    std::shared_ptr<const ObjectModel> model;
    Pose pose;
    geometry::Box world_box;  ///< the model at pose (hill-climbing, grown over the rounding)
  };
  /// A part wider than this many grid cells is kept in the list every query scans.
  static constexpr std::uint64_t kMaxCellsPerPart = 64;

  /// An empty overlay on `index`; cell_size 0 chooses 1/64 of the mesh box's longest side.
  /// @throw InputError for a null index or a negative or non-finite cell size.
  explicit DynamicObstacles(std::shared_ptr<const CollisionIndex> index, double cell_size = 0);
  ~DynamicObstacles();
  DynamicObstacles(DynamicObstacles&&) noexcept;
  DynamicObstacles& operator=(DynamicObstacles&&) noexcept;

  /// A new part: `mesh` (built into an ObjectModel, tens of microseconds for 100 triangles) or
  /// a shared model, at `pose`. Returns its id.
  /// @throw InputError for a mesh ObjectModel rejects, a null model, a bad pose (as
  ///        FlyingObject::query: non-finite, non-unit, a translation beyond
  ///        kMaxCoordinateMagnitude), or a name save could not write back (a line break, or
  ///        more than kMaxObstacleNameBytes bytes).
  DynamicPartId insert(TriangleSoup mesh, const Pose& pose, std::string name = {});
  DynamicPartId insert(std::shared_ptr<const ObjectModel> model, const Pose& pose,
                       std::string name = {});
  /// @throw InputError for an unknown id, and as insert for the pose.
  void move(DynamicPartId id, const Pose& pose);
  /// @throw InputError for an unknown id.
  void remove(DynamicPartId id);
  /// The part, or null for an unknown id (valid until the next change).
  const Part* find(DynamicPartId id) const;
  std::size_t size() const { return parts_.size(); }
  /// Every part, in no particular order (valid until the next change).
  const std::vector<Part>& parts() const { return parts_; }

  /// Hides a part of the index (its environment_part id) from every answer, or shows it again.
  /// @throw InputError for a part the index does not list.
  void hide_part(std::uint32_t part);
  void show_part(std::uint32_t part);
  bool hidden(std::uint32_t part) const { return part < hidden_.size() && hidden_[part] != 0; }
  bool hides_any() const { return hidden_count_ > 0; }
  /// The hidden parts, ascending.
  std::vector<std::uint32_t> hidden_parts() const;

  /// Calls visit(part) for each part whose world box meets `box` (closed boxes), once each,
  /// until visit returns false.
  template <class Visit>
  void for_each_in_box(const geometry::Box& box, Visit&& visit) const;

  /// Bumped by every change.
  std::uint64_t version() const { return version_; }
  /// Bumped by every show_part (a shown part may hold an object that was free while hidden).
  std::uint64_t shows() const { return shows_; }
  double cell_size() const { return cell_size_; }
  const std::shared_ptr<const CollisionIndex>& index() const { return index_; }

  /// Writes the overlay (parts, names, poses, meshes, hidden parts) to `path` as text
  /// (the format is described in DynamicObstaclesFile.cpp), under a temporary name renamed
  /// when complete (OutputFile.h). Coordinates are written as hexadecimal floats: they read
  /// back bit for bit. It replaces nothing but a regular file that is empty or an overlay
  /// already, and never the index's own file.
  /// @throw InputError for a `path` it refuses; IoError when the file cannot be written.
  void save(const std::filesystem::path& path) const;
  /// An overlay on `index` read from `path`: the same ids, names, poses, meshes and hidden
  /// parts (ids inserted later continue after the saved ones).
  /// @throw IoError for a path that is not a regular file (a FIFO, a device); FormatError
  ///        naming the file and the line at fault for a missing, truncated or malformed file
  ///        (a line longer than the format allows too), or one that does not fit `index` (a
  ///        hidden part it does not list).
  static DynamicObstacles load(std::shared_ptr<const CollisionIndex> index,
                               const std::filesystem::path& path, double cell_size = 0);

 private:
  using CellKey = std::uint64_t;
  struct CellRange {
    std::array<std::int64_t, 3> lo{}, hi{};
    std::uint64_t count() const;
  };
  geometry::Box placed_box(const ObjectModel& model, const Pose& pose, DynamicPartId id) const;
  CellRange cells_of(const geometry::Box& box) const;
  static CellKey key(std::int64_t x, std::int64_t y, std::int64_t z);
  static std::array<std::int64_t, 3> coordinates(CellKey key);
  void add_to_grid(std::uint32_t slot);
  void remove_from_grid(std::uint32_t slot);
  std::uint32_t slot_of(DynamicPartId id, const char* action) const;

  std::shared_ptr<const CollisionIndex> index_;
  double cell_size_ = 1;
  std::vector<Part> parts_;                                ///< dense: removal swaps in the last
  std::unordered_map<DynamicPartId, std::uint32_t> slot_;  ///< id -> position in parts_
  std::unordered_map<CellKey, std::vector<DynamicPartId>> grid_;
  std::vector<DynamicPartId> wide_;  ///< parts wider than kMaxCellsPerPart cells
  DynamicPartId next_id_ = 1;
  std::vector<std::uint8_t> hidden_;  ///< by index part
  std::uint32_t hidden_count_ = 0;
  std::uint64_t version_ = 0;
  std::uint64_t shows_ = 0;
};

template <class Visit>
void DynamicObstacles::for_each_in_box(const geometry::Box& box, Visit&& visit) const {
  if (parts_.empty()) return;
  for (const DynamicPartId id : wide_) {
    const Part& part = parts_[slot_.at(id)];
    if (geometry::boxes_overlap(part.world_box, box) && !visit(part)) return;
  }
  const CellRange range = cells_of(box);
  // A part in several cells is visited in one: the first cell it shares with the box (no
  // scratch to deduplicate with, so readers share nothing and visits may nest).
  auto visit_cell = [&](std::int64_t x, std::int64_t y, std::int64_t z,
                        const std::vector<DynamicPartId>& ids) {
    for (const DynamicPartId id : ids) {
      const Part& part = parts_[slot_.at(id)];
      if (!geometry::boxes_overlap(part.world_box, box)) continue;
      const CellRange own = cells_of(part.world_box);
      if (x != std::max(own.lo[0], range.lo[0]) || y != std::max(own.lo[1], range.lo[1]) ||
          z != std::max(own.lo[2], range.lo[2]))
        continue;
      if (!visit(part)) return false;
    }
    return true;
  };
  if (range.count() > grid_.size()) {
    // A box wider than the occupied cells: every occupied cell.
    for (const auto& [cell, ids] : grid_) {
      const auto [x, y, z] = coordinates(cell);
      if (!visit_cell(x, y, z, ids)) return;
    }
    return;
  }
  for (std::int64_t x = range.lo[0]; x <= range.hi[0]; ++x)
    for (std::int64_t y = range.lo[1]; y <= range.hi[1]; ++y)
      for (std::int64_t z = range.lo[2]; z <= range.hi[2]; ++z)
        if (const auto cell = grid_.find(key(x, y, z)); cell != grid_.end())
          if (!visit_cell(x, y, z, cell->second)) return;
}

}  // namespace tetrapage
