#pragma once
/// @file StudyMethod.h
/// The study's four in-core methods (Held, Klosowski, Mitchell, sections 2 and 3) behind one
/// interface, so that the flight benchmark replays the same poses through each of them with
/// the same primitives (the geometry kernel's exact triangle/triangle test): the grid of
/// boxes, the 3d-tree, the R-tree and the conforming tetrahedral mesh.
///
/// Every method answers the study's question: does some triangle of the flying object meet
/// some obstacle triangle (closed sets, touching counts)? Like the study, none of them decides
/// whether the object lies inside an obstacle.

#include <cstdint>
#include <span>
#include <string>

#include <nlohmann/json.hpp>

#include "tetrapage/study/PlacedObject.h"

namespace tetrapage::study {

/// What one query did, added up over a flight (the study's Tables 5-7 print them per step).
struct StudyCounters {
  std::uint64_t queries = 0;
  std::uint64_t full_checks = 0;    ///< queries whose phase I found a witness (phase II ran)
  std::uint64_t collisions = 0;     ///< queries answered "collides"
  std::uint64_t cells_visited = 0;  ///< cV: grid voxels visited (phases I and II)
  std::uint64_t nodes_visited = 0;  ///< nV: tree nodes visited (phases I and II)
  std::uint64_t tets_occupied = 0;  ///< nO: mesh tets enumerated by phase I's box search
  std::uint64_t triangle_tests = 0; ///< exact triangle/triangle tests (phase II)

  StudyCounters& operator+=(const StudyCounters& other);
};

/// The figures of a built method (the study's Table 1 and Tables 5-7 columns).
struct StudyStatistics {
  std::uint64_t obstacle_triangles = 0;
  std::uint64_t stored_triangles = 0;  ///< #(Tst): triangle references over all cells/leaves/tets
  std::uint32_t height = 0;            ///< "Hght": the tree's height (0 for the grid)
  std::uint64_t bytes = 0;             ///< the method's own structures
  double build_seconds = 0;
  nlohmann::json details = nlohmann::json::object();  ///< method-specific figures
};

class StudyMethod {
 public:
  virtual ~StudyMethod() = default;

  /// "grid", "3d-tree", "r-tree" or "mesh".
  virtual std::string name() const = 0;
  /// The parameters, as tables print them ("N=40", "K=10, axis (c), no-gain 5", ...).
  virtual std::string parameters() const = 0;

  /// The two-phase static check of the study at the object's current placement: phase I with
  /// the object's box, phase II (every object triangle against the obstacle triangles near it,
  /// exact) only when phase I finds a witness. Exact answer. Not const: the mesh method keeps
  /// the object's location from step to step.
  virtual bool collides(const PlacedObject& object, StudyCounters& counters) = 0;

  virtual StudyStatistics statistics() const = 0;
};

}  // namespace tetrapage::study
