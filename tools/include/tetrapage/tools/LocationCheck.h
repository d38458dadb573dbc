#pragma once
/// @file LocationCheck.h
/// Checks a point locator (the runtime's locate_point, or any other) against Embree: for each
/// point, a segment is shot from the reference point of a known tet to it through the scene of
/// the mesh's faces (EmbreeMeshFaces), and stepping across the faces it crosses names the tet
/// that holds it. Points are drawn at random in and around the mesh box and placed exactly on
/// faces, edges and vertices of the mesh (checked with the exact predicates).
///
/// The verdict is robust although Embree works in float. A point on a shared face, edge or
/// vertex belongs to every tet around it, and a point within float error of one may be put in
/// the wrong tet by Embree; so the located tet is accepted when it is Embree's tet, or when it
/// shares a vertex with one of the tets Embree's trace ended in (or left the mesh from) and the
/// exact point-in-tet predicate says it holds the point. "Outside" is accepted only when a hull
/// face of a tet around Embree's answer has the point strictly beyond its plane (exact), which
/// proves the point is outside the convex mesh. Every other answer is a disagreement.

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "tetrapage/formats/index/TetMesh.h"
#include "tetrapage/runtime/geometry/Shapes.h"
#include "tetrapage/tools/EmbreeMeshFaces.h"

namespace tetrapage {

enum class LocationPointKind : std::uint8_t { random, on_face, on_edge, on_vertex };
inline constexpr std::size_t kLocationPointKinds = 4;
/// "random", "on face", "on edge", "on vertex".
const char* to_string(LocationPointKind kind);

struct LocationPoint {
  geometry::Point point{};
  LocationPointKind kind = LocationPointKind::random;
  /// The tet Embree shoots from (its walk reference point) and the tet the locator starts at.
  std::uint32_t embree_start = 0;
  std::uint32_t locator_start = 0;
};

struct LocationPointOptions {
  std::uint64_t points = 100'000;
  std::uint64_t seed = 1;
  /// Shares of random, on-face and on-edge points; the rest are mesh vertices.
  double random_share = 0.5;
  double face_share = 0.2;
  double edge_share = 0.2;
  /// Random points are uniform in the mesh box grown by this fraction of its size on each
  /// side, so that some lie outside the mesh.
  double outside_margin = 0.025;
};

struct LocationPointSet {
  std::vector<LocationPoint> points;
  std::array<std::uint64_t, kLocationPointKinds> count{};
  /// Distinct points per kind: a mesh whose vertices carry all 53 bits has about one exact
  /// double point inside each face, so these repeat (from other start tets each time).
  std::array<std::uint64_t, kLocationPointKinds> distinct{};
  /// Candidates constructed per kind (for faces and edges, every dyadic combination of the
  /// corners up to a denominator of 32 and 256); only those computed without rounding that the
  /// exact predicates put on the face or edge are kept.
  std::array<std::uint64_t, kLocationPointKinds> attempts{};
};

/// Draws the points (deterministic for a seed). On-face and on-edge points are drawn from all
/// the dyadic combinations of each face's or edge's corners that are computed without rounding
/// (checked with fma and TwoSum) and that locate_in_tetrahedron puts, exactly, in the relative
/// interior of that face or edge; vertices are exact as they are. A mesh with no such point on
/// any face (or edge) gets none of that kind: see `count`.
/// @throw InputError if the mesh has no tet, the shares are not in [0, 1] or sum above 1, or
///        no tet has a walk reference point.
LocationPointSet make_location_points(const TetMesh& mesh, const LocationPointOptions& options);

/// The locator under test: the tet holding p, or TetMesh::no_neighbour for "outside", found
/// starting from start_tet. Must be thread-safe.
using PointLocator = std::function<std::uint32_t(const geometry::Point& p, std::uint32_t start_tet)>;

/// The runtime's walk (locate_point) on the mesh, which must outlive the locator.
PointLocator runtime_locator(const TetMesh& mesh);

struct LocationDisagreement {
  geometry::Point point{};
  LocationPointKind kind = LocationPointKind::random;
  /// What the locator said (no_neighbour: outside) and where Embree's trace ended.
  std::uint32_t located_tet = TetMesh::no_neighbour;
  std::vector<std::uint32_t> embree_tets;
  bool embree_outside = false;
  std::string reason;
};

/// Outcomes for one kind of point.
struct LocationOutcomes {
  std::uint64_t points = 0;
  /// The located tet is the one tet Embree's trace ended in (and holds the point, exactly).
  std::uint64_t same_tet = 0;
  /// Ties decided by the exact predicates: another tet around Embree's answer that holds
  /// the point, or "outside" (proven by a hull face) where Embree's trace ended inside.
  std::uint64_t exact_ties = 0;
  /// Outside for the locator and for Embree, proven outside by a hull face.
  std::uint64_t outside = 0;
  std::uint64_t disagreements = 0;
  /// Embree traces that had to start again after an inconsistent hit (FaceTrace::resyncs),
  /// and that ended with a choice of several tets.
  std::uint64_t resynced_traces = 0;
  std::uint64_t ambiguous_ends = 0;
};

struct LocationCheckOptions {
  /// Worker threads; 0: all cores.
  unsigned threads = 0;
  /// A progress bar on stderr.
  bool progress = false;
  /// Disagreements kept in the summary (all are counted).
  std::size_t max_listed = 100'000;
};

struct LocationCheckSummary {
  std::array<LocationOutcomes, kLocationPointKinds> by_kind{};
  std::uint64_t points = 0;
  std::uint64_t disagreements = 0;
  std::vector<LocationDisagreement> listed;
  /// Embree: faces hit over all segments, and the sums of the per-kind trace counts.
  std::uint64_t faces_hit = 0;
  std::uint64_t resynced_traces = 0;
  std::uint64_t ambiguous_ends = 0;
  double seconds = 0;
};

/// Checks the locator on every point, in parallel; results do not depend on the thread count.
/// @throw InputError if a point's start tet is out of range or a point is not finite.
/// @throw whatever the locator throws.
LocationCheckSummary check_locations(const EmbreeMeshFaces& faces,
                                     std::span<const LocationPoint> points,
                                     const PointLocator& locator,
                                     const LocationCheckOptions& options = {});

}  // namespace tetrapage
