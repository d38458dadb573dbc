#pragma once
/// @file TriangleRecord.h
/// The triangle record every preprocess stage carries, and the in-memory soups cut into tasks
/// for the passes that visit every triangle.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/preprocess/SoupSpill.h"
#include "tetrapage/runtime/geometry/Shapes.h"

namespace tetrapage {

// One triangle on its way through the pipeline (88 bytes).
struct TriangleRecord {
  geometry::Triangle triangle;
  std::uint64_t id;    // position in the input order, over all parts
  std::uint32_t part;  // part id over all inputs
  std::uint32_t tet;   // after binning: the tet this copy belongs to
};

inline Vec3 centroid(const geometry::Triangle& t) {
  return {(t[0][0] + t[1][0] + t[2][0]) / 3, (t[0][1] + t[1][1] + t[2][1]) / 3,
          (t[0][2] + t[1][2] + t[2][2]) / 3};
}

// The in-memory soups cut into tasks of at most kTaskTriangles consecutive triangles of one
// piece, for the passes that visit every triangle on all threads.
struct InMemoryTask {
  std::size_t piece, first, count;
};
constexpr std::size_t kTaskTriangles = std::size_t(1) << 15;

inline std::vector<InMemoryTask> in_memory_tasks(const SoupSpill<TriangleRecord>& soups) {
  std::vector<InMemoryTask> tasks;
  for (std::size_t p = 0; p < soups.piece_count(); ++p)
    for (std::size_t first = 0; first < soups.piece_size(p); first += kTaskTriangles)
      tasks.push_back({p, first, std::min(kTaskTriangles, soups.piece_size(p) - first)});
  return tasks;
}

}  // namespace tetrapage
