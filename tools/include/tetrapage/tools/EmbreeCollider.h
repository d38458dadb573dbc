#pragma once
/// @file EmbreeCollider.h
/// A second reference for the collision answers, built on Embree's own collision query,
/// rtcCollide, which intersects the BVHs of two scenes and hands back the pairs of
/// primitives whose boxes may meet. In Embree 3 it works only on scenes made entirely of
/// user geometries: each triangle is a user primitive whose box Embree asks for through a
/// bounds callback, and the caller decides each candidate pair.
///
/// Here the environment is one user geometry built once; the object is another, whose
/// vertices are placed per pose with apply_pose() (formats/Pose.h, the placement every
/// answer uses) and whose scene is committed again for each pose. Each candidate pair is
/// decided by CGAL's exact-predicate triangle/triangle test (Epick) on the placed doubles,
/// so nothing of the runtime's kernel is involved.
///
/// Embree keeps boxes in float. Are its bounds conservative? Yes, given conservative input:
/// the boxes handed to it are the double boxes rounded outward (each float box contains its
/// double triangle); Embree's tree nodes are unions of them (min/max, exact in float), a
/// refit recomputes those unions, and rtcCollide compares boxes with <=, touching included.
/// Two triangles that meet share a point, which lies in both float boxes at every level, so
/// the pair is reported: the candidates are a superset of the touching pairs, and
/// surfaces_touch equals the exact oracle's (ReferenceCollider::Answer::surfaces_touch).
/// (Boxes rounded to nearest would also keep every touching pair, rounding being monotone;
/// boxes rounded inward would lose contacts in a plane no float holds: the tests show it.)
/// Embree drops primitives whose box is not finite or reaches about 1.8e18; coordinates
/// beyond 1e18 are refused. What rtcCollide cannot see is one body lying wholly inside
/// the other (the oracle's object_inside and obstacle_inside, decided by ray parity): no
/// surfaces meet there.

#include <cstdint>
#include <memory>

#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/formats/mesh/Pose.h"

namespace tetrapage {

class EmbreeCollider {
 public:
  struct Answer {
    bool surfaces_touch = false;        ///< touching_pairs > 0
    std::uint64_t candidate_pairs = 0;  ///< pairs rtcCollide reported (all pairs of two
                                        ///< leaves whose float boxes overlap)
    std::uint64_t exact_tests = 0;      ///< candidates whose double boxes overlap, each
                                        ///< decided by the exact test
    std::uint64_t touching_pairs = 0;   ///< pairs of triangles that meet
  };

  /// Builds the environment's scene (the expensive part) and the object's geometry.
  /// `threads` = 0: Embree's own default (every hardware thread).
  /// @throw InputError if either soup has no triangle, or a coordinate is beyond the range
  ///        Embree accepts in its float boxes (|x| >= 1e18: it would drop that triangle).
  /// @throw Error if Embree fails (names the call and Embree's message).
  EmbreeCollider(const TriangleSoup& environment, const TriangleSoup& object, unsigned threads = 0);
  ~EmbreeCollider();
  EmbreeCollider(EmbreeCollider&&) noexcept;
  EmbreeCollider& operator=(EmbreeCollider&&) noexcept;

  /// Answers one pose: places the object, commits its scene, calls rtcCollide.
  /// Not thread-safe (the object's scene is rebuilt in place); Embree's own threads run the
  /// traversal; every count is a sum over the pairs, so none depends on their number or order.
  /// @throw InputError if the pose places a vertex beyond Embree's range (|x| >= 1e18).
  /// @throw Error if Embree fails.
  Answer query(const Pose& pose);

  class Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace tetrapage
