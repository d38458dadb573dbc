#include "tetrapage/study/StudyMethod.h"

#include "Obstacles.h"
#include "tetrapage/formats/base/Error.h"

namespace tetrapage::study {

StudyCounters& StudyCounters::operator+=(const StudyCounters& other) {
  queries += other.queries;
  full_checks += other.full_checks;
  collisions += other.collisions;
  cells_visited += other.cells_visited;
  nodes_visited += other.nodes_visited;
  tets_occupied += other.tets_occupied;
  triangle_tests += other.triangle_tests;
  return *this;
}

Obstacles::Obstacles(std::span<const geometry::Triangle> input, const std::string& method) {
  if (input.empty()) throw InputError(method + ": no obstacle triangles");
  triangles.assign(input.begin(), input.end());
  boxes.reserve(input.size());
  for (std::size_t t = 0; t < input.size(); ++t) {
    if (!geometry::is_finite(input[t]))
      throw InputError(method + ": obstacle triangle " + std::to_string(t) + " has a non-finite coordinate");
    boxes.push_back(geometry::box_of(input[t]));
    bounds.extend(boxes.back());
  }
}

}  // namespace tetrapage::study
