// The study's grid of boxes (section 3.1): N x N x N voxels over the obstacles' box, each with
// the list of the obstacle triangles that meet it (exact triangle/box test).

#include <chrono>
#include <cmath>

#include "Obstacles.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/runtime/geometry/TriangleBox.h"
#include "tetrapage/study/BoxMethods.h"

namespace tetrapage::study {
namespace {

class GridMethod final : public StudyMethod {
 public:
  GridMethod(std::span<const geometry::Triangle> input, const GridOptions& options)
      : obstacles_(input, "grid method"), n_(options.cells_per_axis), stamps_(input.size()) {
    if (n_ == 0 || n_ > 1024) throw InputError("grid method: N must be 1..1024, not " + std::to_string(n_));
    const auto start = std::chrono::steady_clock::now();
    // Cut positions computed once: neighbouring voxels share their bounds bit for bit, so the
    // voxels tile the box with no gap.
    for (int a = 0; a < 3; ++a) {
      cuts_[a].resize(n_ + 1);
      for (unsigned i = 0; i <= n_; ++i)
        cuts_[a][i] = obstacles_.bounds.lo[a] + (obstacles_.bounds.hi[a] - obstacles_.bounds.lo[a]) * i / n_;
      cuts_[a][n_] = obstacles_.bounds.hi[a];
    }
    // Two passes over the triangles: counts, then lists (CSR).
    offsets_.assign(std::size_t(n_) * n_ * n_ + 1, 0);
    for (int pass = 0; pass < 2; ++pass) {
      if (pass == 1) {
        for (std::size_t c = 1; c < offsets_.size(); ++c) offsets_[c] += offsets_[c - 1];
        cell_triangles_.resize(offsets_.back());
      }
      std::vector<std::uint64_t> fill(pass == 1 ? offsets_.begin() : offsets_.end(), offsets_.end());
      for (std::uint32_t t = 0; t < obstacles_.size(); ++t) {
        const Range r = cells_of(obstacles_.boxes[t]);
        for (unsigned z = r.lo[2]; z <= r.hi[2]; ++z)
          for (unsigned y = r.lo[1]; y <= r.hi[1]; ++y)
            for (unsigned x = r.lo[0]; x <= r.hi[0]; ++x) {
              if (!geometry::triangle_intersects_box(obstacles_.triangles[t], cell_box(x, y, z))) continue;
              const std::size_t c = cell_index(x, y, z);
              if (pass == 0)
                ++offsets_[c + 1];
              else
                cell_triangles_[fill[c]++] = t;
            }
      }
    }
    build_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }

  std::string name() const override { return "grid"; }
  std::string parameters() const override { return "N=" + std::to_string(n_); }

  bool collides(const PlacedObject& object, StudyCounters& counters) override {
    const geometry::Box& box = object.box();
    return two_phase_check(
        object, counters,
        [&](const geometry::Box& b) { return geometry::boxes_overlap(b, obstacles_.bounds) && find_witness(b, counters); },
        [&](std::size_t i) {
          // Each object triangle against the triangles of the voxels its box meets.
          const geometry::Triangle& t = object.triangles()[i];
          const geometry::Box& t_box = object.triangle_boxes()[i];
          if (!geometry::boxes_overlap(t_box, obstacles_.bounds)) return false;
          stamps_.next_round();
          const Range r = cells_of(t_box);
          for (unsigned z = r.lo[2]; z <= r.hi[2]; ++z)
            for (unsigned y = r.lo[1]; y <= r.hi[1]; ++y)
              for (unsigned x = r.lo[0]; x <= r.hi[0]; ++x) {
                ++counters.cells_visited;
                const std::size_t c = cell_index(x, y, z);
                for (std::uint64_t k = offsets_[c]; k < offsets_[c + 1]; ++k) {
                  const std::uint32_t o = cell_triangles_[k];
                  if (!stamps_.first_visit(o) || !geometry::boxes_overlap(obstacles_.boxes[o], box)) continue;
                  if (obstacles_.meets(t, t_box, o, counters)) return true;
                }
              }
          return false;
        });
  }

  StudyStatistics statistics() const override {
    StudyStatistics s;
    s.obstacle_triangles = obstacles_.size();
    s.stored_triangles = cell_triangles_.size();
    s.bytes = obstacles_.bytes() + offsets_.capacity() * sizeof(std::uint64_t) +
              cell_triangles_.capacity() * sizeof(std::uint32_t) + stamps_.bytes();
    s.build_seconds = build_seconds_;
    std::uint64_t empty = 0;
    for (std::size_t c = 0; c + 1 < offsets_.size(); ++c) empty += offsets_[c] == offsets_[c + 1];
    s.details = {{"cells", offsets_.size() - 1}, {"empty_cells", empty}};
    return s;
  }

 private:
  struct Range {
    std::array<unsigned, 3> lo, hi;
  };

  // The voxels whose closed boxes meet the closed box `b` (which must meet the bounds).
  Range cells_of(const geometry::Box& b) const {
    Range r;
    for (int a = 0; a < 3; ++a) {
      r.lo[a] = first_cell_reaching(a, b.lo[a]);
      r.hi[a] = last_cell_starting(a, b.hi[a]);
    }
    return r;
  }
  // The voxel x falls in, up to rounding (the callers step to the exact one); `flat` for an
  // axis of zero extent.
  unsigned guess(int a, double x, unsigned flat) const {
    const auto& c = cuts_[a];
    if (!(c[n_] > c[0])) return flat;
    return unsigned(std::clamp((x - c[0]) / (c[n_] - c[0]) * n_, 0.0, double(n_ - 1)));
  }
  // Smallest i with cuts[i + 1] >= x: the first voxel whose upper bound reaches x.
  unsigned first_cell_reaching(int a, double x) const {
    const auto& c = cuts_[a];
    unsigned i = guess(a, x, 0);
    while (i > 0 && c[i] >= x) --i;
    while (i + 1 < n_ && c[i + 1] < x) ++i;
    return i;
  }
  // Largest i with cuts[i] <= x: the last voxel whose lower bound is not beyond x.
  unsigned last_cell_starting(int a, double x) const {
    const auto& c = cuts_[a];
    unsigned i = guess(a, x, n_ - 1);
    while (i + 1 < n_ && c[i + 1] <= x) ++i;
    while (i > 0 && c[i] > x) --i;
    return i;
  }
  geometry::Box cell_box(unsigned x, unsigned y, unsigned z) const {
    geometry::Box b;
    b.lo = {cuts_[0][x], cuts_[1][y], cuts_[2][z]};
    b.hi = {cuts_[0][x + 1], cuts_[1][y + 1], cuts_[2][z + 1]};
    return b;
  }
  std::size_t cell_index(unsigned x, unsigned y, unsigned z) const {
    return (std::size_t(z) * n_ + y) * n_ + x;
  }

  bool find_witness(const geometry::Box& box, StudyCounters& counters) const {
    const Range r = cells_of(box);
    for (unsigned z = r.lo[2]; z <= r.hi[2]; ++z)
      for (unsigned y = r.lo[1]; y <= r.hi[1]; ++y)
        for (unsigned x = r.lo[0]; x <= r.hi[0]; ++x) {
          ++counters.cells_visited;
          const std::size_t c = cell_index(x, y, z);
          for (std::uint64_t k = offsets_[c]; k < offsets_[c + 1]; ++k)
            if (geometry::boxes_overlap(obstacles_.boxes[cell_triangles_[k]], box)) return true;
        }
    return false;
  }

  Obstacles obstacles_;
  unsigned n_;
  std::array<std::vector<double>, 3> cuts_;
  std::vector<std::uint64_t> offsets_;
  std::vector<std::uint32_t> cell_triangles_;
  VisitStamps stamps_;
  double build_seconds_ = 0;
};

}  // namespace

std::unique_ptr<StudyMethod> make_grid_method(std::span<const geometry::Triangle> obstacles,
                                              const GridOptions& options) {
  return std::make_unique<GridMethod>(obstacles, options);
}

}  // namespace tetrapage::study
