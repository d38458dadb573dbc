#pragma once
/// @file FclModel.h
/// FCL BVH models of triangle soups, shared by the FCL peers (FclCollider, FclDistance).
/// Private to bench/peers/src: it includes FCL's headers, which the public headers keep out.

#include <fcl/geometry/bvh/BVH_model.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/formats/mesh/Pose.h"

namespace tetrapage::fcl_model {

/// A BVHModel<BV> of `soup` (FCL copies the coordinates). `who` and `what` name the peer and
/// the soup in errors ("FCL collider", "environment").
/// @throw InputError for an empty soup; Error when FCL refuses the model (its status code).
template <class BV>
std::shared_ptr<fcl::BVHModel<BV>> build(const TriangleSoup& soup, const std::string& who, const char* what,
                                         const char* bv_name) {
  if (soup.triangles.empty()) throw InputError(who + ": the " + what + " has no triangle");
  std::vector<fcl::Vector3d> points;
  points.reserve(soup.vertices.size());
  for (const auto& v : soup.vertices) points.emplace_back(v[0], v[1], v[2]);
  std::vector<fcl::Triangle> triangles;
  triangles.reserve(soup.triangles.size());
  for (const auto& t : soup.triangles) triangles.emplace_back(t[0], t[1], t[2]);
  auto model = std::make_shared<fcl::BVHModel<BV>>();
  int status = model->beginModel(int(triangles.size()), int(points.size()));
  if (status == fcl::BVH_OK) status = model->addSubModel(points, triangles);
  if (status == fcl::BVH_OK) status = model->endModel();
  if (status != fcl::BVH_OK)
    throw Error(who + ": BVHModel<" + bv_name + "> of the " + what + " failed with status " + std::to_string(status));
  return model;
}

/// The arrays a built BVHModel holds: BV nodes, triangles with their primitive indices, vertices.
/// (BVHModel::memUsage returns a status code in FCL 0.7 and sums in int, so it cannot say.)
template <class BV>
std::uint64_t bytes(const fcl::BVHModel<BV>& model) {
  return std::uint64_t(model.getNumBVs()) * sizeof(fcl::BVNode<BV>) +
         std::uint64_t(model.num_tris) * (sizeof(fcl::Triangle) + sizeof(unsigned int)) +
         std::uint64_t(model.num_vertices) * sizeof(fcl::Vector3d);
}

/// The object's transform for `pose`: rotation_matrix(q) and t, the matrix apply_pose uses;
/// with the environment at the identity, FCL's relative transform is exactly this one.
inline fcl::Transform3d transform_of(const Pose& pose) {
  const auto r = rotation_matrix(pose.rotation);
  fcl::Transform3d transform = fcl::Transform3d::Identity();
  transform.linear() << r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8];
  transform.translation() << pose.translation[0], pose.translation[1], pose.translation[2];
  return transform;
}

}  // namespace tetrapage::fcl_model
