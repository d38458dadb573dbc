#pragma once
/// @file EmbreeMeshFaces.h
/// The faces of a coarse tet mesh as an Embree 3 scene, each face once, so that a segment
/// shot through the mesh reports every face it crosses; stepping across those faces in order
/// from a known tet tells which tet holds the segment's end. This is the independent
/// reference for the runtime's walk (MeshWalk.h): it shares no walking code with it, only the
/// mesh. Embree works in float (vertices are rounded after moving the mesh box's centre to the
/// origin) and reports hits within float error; FaceTrace says where that leaves a choice, and
/// the callers decide such ties with the exact predicates.

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "tetrapage/formats/index/TetMesh.h"
#include "tetrapage/runtime/geometry/Shapes.h"

namespace tetrapage {

/// One face of the mesh: the tet that lists it and the tet across it.
struct MeshFace {
  std::array<std::uint32_t, 3> vertices{};
  std::uint32_t tet = 0;
  /// no_neighbour when the face is on the hull.
  std::uint32_t other = TetMesh::no_neighbour;
};

/// A face met by a segment a -> b at a + t (b - a), t in [0, 1] (float, as Embree found it).
struct FaceHit {
  float t = 0;
  std::uint32_t face = 0;
};

/// Where stepping across the faces hit along a segment ends.
struct FaceTrace {
  /// Tets that may hold the segment's end: one, unless hits at about the same t (the segment
  /// passes within float error of an edge or a vertex, or ends on a face, edge or vertex) left
  /// several; empty when the segment left the mesh and did not come back.
  std::vector<std::uint32_t> end_tets;
  /// The segment crossed a hull face at its last hits: its end is outside (within float error).
  bool outside = false;
  /// The tets whose hull face the segment crossed.
  std::vector<std::uint32_t> exit_tets;
  /// Distinct faces hit.
  std::uint32_t faces_hit = 0;
  /// Groups of hits none of whose faces bounds a tet the trace could be in (a face Embree
  /// missed or reported spuriously); the trace starts again from the tets of that group.
  std::uint32_t resyncs = 0;
};

class EmbreeMeshFaces {
 public:
  /// Builds the scene of the mesh's faces (each shared face once, hull faces included).
  /// `threads` = 0 lets Embree use every hardware thread. The mesh must outlive this object.
  /// @throw InputError if the mesh has no tet, a corner or neighbour index out of range, or
  ///        neighbours that do not list each other.
  /// @throw Error if Embree fails (the message carries Embree's reason).
  explicit EmbreeMeshFaces(const TetMesh& mesh, unsigned threads = 0);
  ~EmbreeMeshFaces();
  EmbreeMeshFaces(EmbreeMeshFaces&&) noexcept;
  EmbreeMeshFaces& operator=(EmbreeMeshFaces&&) noexcept;
  EmbreeMeshFaces(const EmbreeMeshFaces&) = delete;
  EmbreeMeshFaces& operator=(const EmbreeMeshFaces&) = delete;

  const TetMesh& mesh() const;
  /// Indexed by Embree's primitive id.
  std::span<const MeshFace> faces() const;
  /// Hits closer than this along a segment (in model units) are grouped as simultaneous:
  /// a few float ulps of the mesh box's extent.
  double tie_distance() const;

  /// Every face the segment a -> b meets, each once, sorted by t. Thread-safe.
  /// @throw InputError if a or b is not finite.
  void hits(const geometry::Point& a, const geometry::Point& b, std::vector<FaceHit>& out) const;

  /// Steps from start_tet, which must hold a, across the faces hit along a -> b in order.
  /// Hits within tie_distance() of each other are taken as one group, crossed in any order
  /// that steps from face to adjacent face. Thread-safe.
  /// @throw InputError if start_tet is out of range or a or b is not finite.
  FaceTrace trace(std::uint32_t start_tet, const geometry::Point& a, const geometry::Point& b) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tetrapage
