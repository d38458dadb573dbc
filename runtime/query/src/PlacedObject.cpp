#include "PlacedObject.h"

#include <cstdio>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/UnitQuaternion.h"

namespace tetrapage {

void check_translation_within_limit(const Vec3& translation) {
  for (int a = 0; a < 3; ++a)
    if (std::fabs(translation[a]) > kMaxCoordinateMagnitude) {
      char text[200];
      std::snprintf(text, sizeof text,
                    "invalid pose: translation %c = %g is beyond %g in magnitude: distances "
                    "from there would overflow",
                    "xyz"[a], translation[a], kMaxCoordinateMagnitude);
      throw InputError(text);
    }
}

PlacedObject::PlacedObject(const ObjectModel& model)
    : model_(&model),
      world_(model.mesh.vertices.size()),
      world_step_(model.mesh.vertices.size(), ~std::uint64_t{0}) {}

void PlacedObject::rebind(const ObjectModel& model) {
  model_ = &model;
  // Entries keep steps older than the next place()'s: stale for the new model too.
  if (world_.size() < model.mesh.vertices.size()) {
    world_.resize(model.mesh.vertices.size());
    world_step_.resize(model.mesh.vertices.size(), ~std::uint64_t{0});
  }
  extreme_ = {};
}

void PlacedObject::place(const Pose& pose) {
  if (!(std::isfinite(pose.translation[0]) && std::isfinite(pose.translation[1]) &&
        std::isfinite(pose.translation[2])) ||
      !is_unit_quaternion(pose.rotation)) {
    char text[200];
    std::snprintf(text, sizeof text,
                  "invalid pose: translation (%g, %g, %g), quaternion (%g, %g, %g, %g)",
                  pose.translation[0], pose.translation[1], pose.translation[2], pose.rotation[0],
                  pose.rotation[1], pose.rotation[2], pose.rotation[3]);
    throw InputError(text);
  }
  // Object coordinates are within the same bound (ObjectModel): R x + t then stays finite.
  check_translation_within_limit(pose.translation);
  // rotation_matrix normalises a q off unit norm: every prune here assumes an orthogonal
  // matrix up to rounding.
  rotation_ = rotation_matrix(pose.rotation);
  translation_ = pose.translation;
  ++step_;
}

geometry::Box PlacedObject::world_box() {
  const ObjectModel& model = *model_;
  geometry::Box box;
  if (model.hull_offsets.empty()) {
    for (const auto v : model.hull_vertices) box.extend(world_vertex(v));
  } else {
    // Per axis and side, climb from the last extreme to a vertex no neighbour beats: on a
    // convex polytope a local extreme of a linear function is the global one. Only the
    // axis's coordinate is computed (apply_pose's row, the same operations).
    for (int k = 0; k < 6; ++k) {
      const int axis = k / 2;
      const double sign = k % 2 == 0 ? -1.0 : 1.0;
      const double r0 = rotation_[3 * axis], r1 = rotation_[3 * axis + 1],
                   r2 = rotation_[3 * axis + 2];
      const auto coordinate = [&](std::uint32_t hull_vertex) {
        const Vec3& x = model.mesh.vertices[model.hull_vertices[hull_vertex]];
        return r0 * x[0] + r1 * x[1] + r2 * x[2] + translation_[axis];
      };
      std::uint32_t at = extreme_[k];
      double best = sign * coordinate(at);
      for (bool moved = true; moved;) {
        moved = false;
        // The neighbours of the vertex the pass started from: `at` moves during the pass.
        const std::uint32_t from = at;
        for (std::uint32_t i = model.hull_offsets[from]; i < model.hull_offsets[from + 1]; ++i) {
          const std::uint32_t next = model.hull_neighbours[i];
          const double value = sign * coordinate(next);
          if (value > best) best = value, at = next, moved = true;
        }
      }
      extreme_[k] = at;
      (k % 2 == 0 ? box.lo[axis] : box.hi[axis]) = sign * best;
    }
  }
  // The placement rounds each coordinate; rounded values can make a near-tie climb stop one
  // vertex short. Grow the box far beyond those roundings (it only prunes).
  const double magnitude = model.radius + translation_magnitude();
  const double margin = magnitude * 0x1p-40;
  for (int a = 0; a < 3; ++a) box.lo[a] -= margin, box.hi[a] += margin;
  return box;
}

}  // namespace tetrapage
