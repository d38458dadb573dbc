#pragma once
// Private to study/: the obstacle triangles every method is built over, with their boxes, and
// the one phase II primitive they all share (box pretest, then the kernel's exact test).

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

}  // namespace tetrapage::study
