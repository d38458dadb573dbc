#pragma once
// Private to study/: the obstacle triangles every method is built over, with their boxes, and
// the one phase II primitive they all share (box pretest, then the kernel's exact test).

#include <algorithm>
#include <span>
#include <string>
#include <vector>

#include "tetrapage/runtime/geometry/Box.h"
#include "tetrapage/runtime/geometry/TriangleTriangle.h"
#include "tetrapage/study/StudyMethod.h"

namespace tetrapage::study {

struct Obstacles {
  std::vector<geometry::Triangle> triangles;
  std::vector<geometry::Box> boxes;
  geometry::Box bounds;

  /// Copies the triangles. @throw InputError (naming `method`) for none or a non-finite one.
  Obstacles(std::span<const geometry::Triangle> input, const std::string& method);

  std::size_t size() const { return triangles.size(); }
  std::uint64_t bytes() const {
    return triangles.capacity() * sizeof(geometry::Triangle) + boxes.capacity() * sizeof(geometry::Box);
  }

  /// Phase II's test of object triangle `t` (with box `t_box`) against obstacle `o`.
  bool meets(const geometry::Triangle& t, const geometry::Box& t_box, std::uint32_t o,
             StudyCounters& counters) const {
    if (!geometry::boxes_overlap(t_box, boxes[o])) return false;
    ++counters.triangle_tests;
    return geometry::triangles_intersect(t, triangles[o]);
  }
};

/// The study's two phases as every box method runs them: phase I, `witness(BB(F))`, looks for an
/// obstacle triangle whose box meets the object's box; only then phase II, `test(i)`, checks the
/// object's triangle i against the obstacles near it (true: they meet), up to the first hit.
template <class Witness, class Test>
bool two_phase_check(const PlacedObject& object, StudyCounters& counters, Witness&& witness, Test&& test) {
  ++counters.queries;
  if (!witness(object.box())) return false;
  ++counters.full_checks;
  for (std::size_t i = 0; i < object.triangle_count(); ++i)
    if (test(i)) {
      ++counters.collisions;
      return true;
    }
  return false;
}

/// Marks the obstacles already looked at for one object triangle, so that a triangle stored
/// in several cells or leaves is tested once: a stamp per obstacle, no clearing between rounds.
class VisitStamps {
 public:
  explicit VisitStamps(std::size_t obstacles) : stamps_(obstacles, 0) {}
  /// Starts a new round: nothing is marked.
  void next_round() {
    if (++round_ == 0) {  // wrapped: clear once every 2^32 rounds
      std::fill(stamps_.begin(), stamps_.end(), 0);
      round_ = 1;
    }
  }
  /// True the first time `obstacle` is seen in this round.
  bool first_visit(std::uint32_t obstacle) {
    if (stamps_[obstacle] == round_) return false;
    stamps_[obstacle] = round_;
    return true;
  }
  std::uint64_t bytes() const { return stamps_.capacity() * sizeof(std::uint32_t); }

 private:
  std::vector<std::uint32_t> stamps_;
  std::uint32_t round_ = 0;
};

}  // namespace tetrapage::study
