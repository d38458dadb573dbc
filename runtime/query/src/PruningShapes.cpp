#include "PruningShapes.h"

namespace tetrapage {

void PruningShapes::prepare(const ObjectModel& model, const PlacedObject& object,
                            const geometry::Box& box, double reach, bool own_frame,
                            bool solid_query, const geometry::Box& model_box) {
  model_ = &model;
  object_ = &object;
  reach_ = reach;
  own_frame_ = own_frame;
  near_surface_only_ = own_frame && !solid_query;
  for (int a = 0; a < 3; ++a) {
    own_centre_[a] = 0.5 * (model.box.lo[a] + model.box.hi[a]);
    own_half_[a] = 0.5 * (model.box.hi[a] - model.box.lo[a]) + reach;
  }
  translation_magnitude_ = object.translation_magnitude();
  surface_test_extent_ =
      0.1 * std::max({model.box.hi[0] - model.box.lo[0], model.box.hi[1] - model.box.lo[1],
                      model.box.hi[2] - model.box.lo[2]});
  plane_margin_ = model.radius * 0x1p-30;
  ball_prunes_ = own_frame && model.ball_prunes;
  ball_reach_ = model.ball_radius * (1 + 0x1p-30);
  // The ball placed in the world (its centre by apply_pose's arithmetic): a world box that
  // misses it misses the object, with no turn into the object's frame. Its radius is grown by
  // the reach and far beyond the placement's rounding.
  world_ball_centre_ = {};
  world_ball_reach_ = 0;
  if (ball_prunes_) {
    world_ball_centre_ = apply_pose(object.rotation(), object.translation(), model.ball_centre);
    world_ball_reach_ =
        ball_reach_ + reach + (model.radius + model.ball_radius + translation_magnitude_) * 0x1p-40;
  }
  // The hull's planes placed in the world, likewise: a world box wholly beyond one misses the
  // object (the tetrahedron's world box is up to five times its volume). Offsets grown by the
  // reach, and by far more than the placement's and this test's roundings over any box of the
  // model.
  world_planes_.clear();
  if (own_frame && !model.hull_planes.empty()) {
    world_planes_.resize(model.hull_planes.size());
    const std::array<double, 9>& rotation = object.rotation();
    const Vec3& translation = object.translation();
    const double magnitude = model.radius + translation_magnitude_ +
                             std::max({std::fabs(model_box.lo[0]), std::fabs(model_box.lo[1]),
                                       std::fabs(model_box.lo[2]), std::fabs(model_box.hi[0]),
                                       std::fabs(model_box.hi[1]), std::fabs(model_box.hi[2])});
    for (std::size_t k = 0; k < model.hull_planes.size(); ++k) {
      const auto& [n, offset] = model.hull_planes[k];
      auto& [w, world_offset] = world_planes_[k];
      for (int a = 0; a < 3; ++a)
        w[a] = rotation[3 * a] * n[0] + rotation[3 * a + 1] * n[1] + rotation[3 * a + 2] * n[2];
      world_offset = offset + w[0] * translation[0] + w[1] * translation[1] +
                     w[2] * translation[2] + reach + plane_margin_ + magnitude * 0x1p-40;
    }
  }
  // Inner R-tree nodes are asked of the object's own box too when the world box is much
  // looser than it (a turned tetrahedron's is up to five times its volume): the subtrees it
  // prunes then pay for the tests, which did not pay for a round object (measured 1 to 3
  // times: 4 triangles +7 % on the 1M and 10M scenes, the others within 1 %).
  constexpr double kLoose = 1.5;
  const double own_volume = (model.box.hi[0] - model.box.lo[0] + 2 * reach) *
                            (model.box.hi[1] - model.box.lo[1] + 2 * reach) *
                            (model.box.hi[2] - model.box.lo[2] + 2 * reach);
  const double world_volume =
      (box.hi[0] - box.lo[0]) * (box.hi[1] - box.lo[1]) * (box.hi[2] - box.lo[2]);
  prune_inner_ = own_frame && world_volume > kLoose * own_volume;
}

}  // namespace tetrapage
