#include "tetrapage/tools/ReferenceCollider.h"

#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/helpers.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <limits>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "tetrapage/formats/base/Error.h"

namespace tetrapage {
namespace {

namespace PMP = CGAL::Polygon_mesh_processing;

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using TriangleIterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, TriangleIterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;
using Mesh = CGAL::Surface_mesh<Point>;
using Side = CGAL::Side_of_triangle_mesh<Mesh, Kernel>;
using FaceTree = Side::AABB_tree;
using SoupTriangle = std::array<std::size_t, 3>;

Point to_point(const Vec3& v) {
  return Point(v[0], v[1], v[2]);
}
Vec3 to_vec3(const Point& p) {
  return {p.x(), p.y(), p.z()};
}

// A closed surface ready for point queries. The face tree is built here: Side_of_triangle_mesh
// would otherwise build it inside the first query, behind a lock. Neither copied nor moved
// (the tree points into the mesh, the side into the tree).
class Solid {
 public:
  explicit Solid(Mesh mesh)
      : mesh_(std::move(mesh)),
        tree_(faces(mesh_).first, faces(mesh_).second, mesh_,
              get(CGAL::vertex_point, std::as_const(mesh_))),
        side_(built(tree_)) {}
  Solid(const Solid&) = delete;
  Solid& operator=(const Solid&) = delete;

  // Strictly inside; a point on the surface is a contact, which the triangle tests decide.
  bool contains(const Point& p) const { return side_(p) == CGAL::ON_BOUNDED_SIDE; }

 private:
  static const FaceTree& built(FaceTree& tree) {
    tree.build();
    return tree;
  }

  Mesh mesh_;
  FaceTree tree_;
  Side side_;
};

// A closed environment component's box as an AABB_tree primitive: the tree finds the
// components whose box holds a point, so a query asks only those.
struct SolidBox {
  Kernel::Iso_cuboid_3 box;
  std::uint32_t solid;
};
class SolidBoxPrimitive {
 public:
  using Id = std::uint32_t;
  using Datum = Kernel::Iso_cuboid_3;
  using Point = Kernel::Point_3;
  using Datum_reference = const Datum&;
  using Point_reference = const Point&;

  explicit SolidBoxPrimitive(std::vector<SolidBox>::const_iterator it)
      : id_(it->solid), box_(it->box), corner_(box_.min()) {}
  Id id() const { return id_; }
  const Datum& datum() const { return box_; }
  const Point& reference_point() const { return corner_; }

 private:
  Id id_;
  Datum box_;
  Point corner_;
};
using SolidBoxTree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, SolidBoxPrimitive>>;

// One connected component of a part: its box, one of its triangles (in the soup), and its
// surface when closed.
struct Component {
  BoundingBox box;
  std::uint32_t first_triangle = 0;
  std::optional<Mesh> closed;
};

struct ComponentSplit {
  std::vector<std::uint32_t> component_of;  // per triangle of the soup
  std::vector<Component> components;
};

// The soup's triangles grouped by part, each group in soup order (no part_of: one part).
std::vector<std::vector<std::uint32_t>> triangles_by_part(const TriangleSoup& soup) {
  std::size_t parts = std::max<std::size_t>(1, soup.part_count());
  for (const auto part : soup.part_of) parts = std::max<std::size_t>(parts, std::size_t(part) + 1);
  std::vector<std::vector<std::uint32_t>> groups(parts);
  for (std::size_t t = 0; t < soup.triangle_count(); ++t)
    groups[soup.part_of.empty() ? 0 : soup.part_of[t]].push_back(std::uint32_t(t));
  return groups;
}

// A part as a polygon soup with every corner its own point, then points merged by exact
// coordinates (CGAL's std::map on Less_xyz_3, where -0.0 equals 0.0): the soup's own vertex
// indices play no part, so STL-style soups and shared indices read the same.
struct MergedPart {
  std::vector<Point> points;
  std::vector<SoupTriangle> triangles;
};
MergedPart merge_part(const TriangleSoup& soup, const std::vector<std::uint32_t>& triangles) {
  MergedPart part;
  part.points.reserve(3 * triangles.size());
  part.triangles.reserve(triangles.size());
  for (const auto t : triangles) {
    const std::size_t first = part.points.size();
    for (const auto& corner : soup.corners(t)) part.points.push_back(to_point(corner));
    part.triangles.push_back({first, first + 1, first + 2});
  }
  PMP::merge_duplicate_points_in_polygon_soup(part.points, part.triangles);
  return part;
}

// Each triangle's component within its part (triangles joined through shared merged points,
// by union-find), numbered in order of first triangle; `count` receives how many.
std::vector<std::uint32_t> label_components(const MergedPart& part, std::uint32_t& count) {
  std::vector<std::size_t> parent(part.points.size());
  for (std::size_t i = 0; i < parent.size(); ++i) parent[i] = i;
  const auto root = [&parent](std::size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];  // path halving
    return i;
  };
  for (const auto& tri : part.triangles)
    for (int k = 1; k < 3; ++k) parent[root(tri[k])] = root(tri[0]);
  constexpr auto kUnset = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> label_of_root(part.points.size(), kUnset);
  std::vector<std::uint32_t> label(part.triangles.size());
  count = 0;
  for (std::size_t t = 0; t < part.triangles.size(); ++t) {
    auto& l = label_of_root[root(part.triangles[t][0])];
    if (l == kUnset) l = count++;
    label[t] = l;
  }
  return label;
}

// Closed as CGAL reads it: the component's soup oriented (points duplicated where it is not
// manifold), made a Surface_mesh, and that mesh closed and all triangles. Empty when open.
std::optional<Mesh> closed_surface(std::vector<Point> points, std::vector<SoupTriangle> triangles) {
  for (const auto& tri : triangles)
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0]) return std::nullopt;  // no face
  PMP::orient_polygon_soup(points, triangles);
  if (!PMP::is_polygon_soup_a_polygon_mesh(triangles)) return std::nullopt;
  Mesh mesh;
  PMP::polygon_soup_to_polygon_mesh(points, triangles, mesh);
  if (!CGAL::is_closed(mesh) || !CGAL::is_triangle_mesh(mesh)) return std::nullopt;
  return mesh;
}

// Splits one part's merged soup into its components' own soups (points renumbered in order
// of use) and appends the components to `split`.
void add_part_components(const std::vector<std::uint32_t>& triangles, const MergedPart& part,
                         ComponentSplit& split) {
  std::uint32_t count = 0;
  const auto label = label_components(part, count);
  const auto base = std::uint32_t(split.components.size());
  split.components.resize(base + count);
  std::vector<std::vector<Point>> points(count);
  std::vector<std::vector<SoupTriangle>> faces(count);
  constexpr auto kUnset = std::numeric_limits<std::size_t>::max();
  std::vector<std::size_t> renumbered(part.points.size(), kUnset);  // points are not shared
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    const std::uint32_t c = label[i];
    Component& component = split.components[base + c];
    if (faces[c].empty()) component.first_triangle = triangles[i];
    split.component_of[triangles[i]] = base + c;
    SoupTriangle tri{};
    for (int k = 0; k < 3; ++k) {
      const std::size_t p = part.triangles[i][k];
      if (renumbered[p] == kUnset) {
        renumbered[p] = points[c].size();
        points[c].push_back(part.points[p]);
        component.box.extend(to_vec3(part.points[p]));
      }
      tri[k] = renumbered[p];
    }
    faces[c].push_back(tri);
  }
  for (std::uint32_t c = 0; c < count; ++c)
    split.components[base + c].closed = closed_surface(std::move(points[c]), std::move(faces[c]));
}

// Components and closedness of a whole soup, part by part.
ComponentSplit split_components(const TriangleSoup& soup) {
  ComponentSplit split;
  split.component_of.resize(soup.triangle_count());
  for (const auto& triangles : triangles_by_part(soup))
    if (!triangles.empty()) add_part_components(triangles, merge_part(soup, triangles), split);
  return split;
}

bool box_within(const BoundingBox& inner, const BoundingBox& outer) {
  for (int a = 0; a < 3; ++a)
    if (inner.lo[a] < outer.lo[a] || inner.hi[a] > outer.hi[a]) return false;
  return true;
}

}  // namespace

class ReferenceCollider::Impl {
 public:
  Impl(const TriangleSoup& environment, const TriangleSoup& object) {
    if (environment.triangles.empty())
      throw InputError("reference collider: the environment has no triangle");
    if (object.triangles.empty())
      throw InputError("reference collider: the object has no triangle");
    environment_triangles_.reserve(environment.triangles.size());
    for (std::size_t t = 0; t < environment.triangles.size(); ++t) {
      const auto c = environment.corners(t);
      environment_triangles_.emplace_back(to_point(c[0]), to_point(c[1]), to_point(c[2]));
    }
    environment_bounds_ = environment.bounds();
    environment_tree_.rebuild(environment_triangles_.begin(), environment_triangles_.end());
    environment_tree_.build();  // now, not lazily inside the first (concurrent) query
    add_environment_components(environment);
    object_vertices_ = object.vertices;
    object_triangles_ = object.triangles;
    for (const auto& v : object_vertices_) {
      object_radius_ = std::max(object_radius_, std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]));
      object_local_box_.extend(v);
    }
    ComponentSplit split = split_components(object);
    for (auto& component : split.components) {
      object_representatives_.push_back(object.triangles[component.first_triangle][0]);
      if (component.closed) object_closed_.push_back(std::move(*component.closed));
    }
  }

  // The object placed at `pose`, its box, and the environment triangles that meet the box.
  void place(const Pose& pose, std::vector<Point>& placed, BoundingBox& box,
             std::vector<Tree::Primitive_id>& candidates) const {
    const auto rotation = rotation_matrix(pose.rotation);
    placed.reserve(object_vertices_.size());
    for (const auto& v : object_vertices_) {
      const Vec3 w = apply_pose(rotation, pose.translation, v);
      box.extend(w);
      placed.push_back(to_point(w));
    }
    const CGAL::Bbox_3 object_box(box.lo[0], box.lo[1], box.lo[2], box.hi[0], box.hi[1], box.hi[2]);
    environment_tree_.all_intersected_primitives(object_box, std::back_inserter(candidates));
  }

  bool surfaces_touch(const Pose& pose) const {
    std::vector<Point> placed;
    BoundingBox box;
    std::vector<Tree::Primitive_id> candidates;
    place(pose, placed, box, candidates);
    return !candidates.empty() && surfaces_touch(placed, candidates);
  }

  Answer query(const Pose& pose) const {
    Answer answer;
    std::vector<Point> placed;
    BoundingBox box;
    std::vector<Tree::Primitive_id> candidates;
    place(pose, placed, box, candidates);
    answer.candidates = candidates.size();
    if (!candidates.empty()) answer.surfaces_touch = surfaces_touch(placed, candidates);
    // With no contact, one vertex of each object component decides for the component.
    if (!answer.surfaces_touch)
      answer.object_inside =
          std::any_of(object_representatives_.begin(), object_representatives_.end(),
                      [&](std::uint32_t v) { return inside(placed[v]); });
    if (!answer.surfaces_touch && !answer.object_inside && !object_closed_.empty() &&
        !candidates.empty())
      answer.obstacle_inside = obstacle_inside(box, candidates, pose);
    answer.collides = answer.surfaces_touch || answer.object_inside || answer.obstacle_inside;
    return answer;
  }

  // Strictly inside some closed environment component; only those whose box holds p are asked.
  bool inside(const Point& p) const {
    if (solids_.empty()) return false;
    std::vector<SolidBoxPrimitive::Id> holding;
    solid_boxes_.all_intersected_primitives(p, std::back_inserter(holding));
    for (const auto solid : holding)
      if (solids_[solid]->contains(p)) return true;
    return false;
  }

  // Some environment component inside a closed object component. Only components with a
  // triangle among the candidates and their whole box in the object's box can be; with no
  // surface contact, one vertex decides for its whole component.
  bool obstacle_inside(const BoundingBox& box, const std::vector<Tree::Primitive_id>& candidates,
                       const Pose& pose) const {
    std::vector<std::uint32_t> components;
    components.reserve(candidates.size());
    for (const auto& id : candidates)
      components.push_back(
          environment_component_[std::size_t(id - environment_triangles_.begin())]);
    std::sort(components.begin(), components.end());
    components.erase(std::unique(components.begin(), components.end()), components.end());
    std::vector<Point> points;
    for (const auto c : components) {
      const EnvironmentComponent& component = environment_components_[c];
      if (box_within(component.box, box) && near_object(component.vertex, pose))
        points.push_back(to_point(component.vertex));
    }
    if (points.empty()) return false;
    // The placed object's closed components, built only for a pose that needs them.
    for (const Mesh& local : object_closed_) {
      const Solid solid(place_mesh(local, pose));
      for (const auto& p : points)
        if (solid.contains(p)) return true;
    }
    return false;
  }

  BoundingBox object_bounds(const Pose& pose) const {
    const auto rotation = rotation_matrix(pose.rotation);
    BoundingBox box;
    for (const auto& v : object_vertices_) box.extend(apply_pose(rotation, pose.translation, v));
    return box;
  }

  const BoundingBox& environment_bounds() const { return environment_bounds_; }
  double object_radius() const { return object_radius_; }
  std::size_t environment_components() const { return environment_components_.size(); }
  std::size_t environment_closed_components() const { return solids_.size(); }
  std::size_t object_components() const { return object_representatives_.size(); }
  std::size_t object_closed_components() const { return object_closed_.size(); }

 private:
  struct EnvironmentComponent {
    BoundingBox box;
    Vec3 vertex;  // one of its vertices
  };

  // The environment's components, a Solid per closed one, and the tree of the closed ones' boxes.
  void add_environment_components(const TriangleSoup& environment) {
    ComponentSplit split = split_components(environment);
    environment_component_ = std::move(split.component_of);
    std::vector<SolidBox> boxes;
    for (auto& component : split.components) {
      environment_components_.push_back(
          {component.box, environment.corners(component.first_triangle)[0]});
      if (!component.closed) continue;
      const BoundingBox& b = component.box;
      boxes.push_back(
          {Kernel::Iso_cuboid_3(to_point(b.lo), to_point(b.hi)), std::uint32_t(solids_.size())});
      solids_.push_back(std::make_unique<Solid>(std::move(*component.closed)));
    }
    if (!boxes.empty()) solid_boxes_.rebuild(boxes.begin(), boxes.end());  // rebuild() builds
  }

  // Whether p, taken back to the object's frame, lies in the object's own box grown by a margin
  // far beyond the rounding: it only prunes, sparing the placed meshes for most poses.
  bool near_object(const Vec3& p, const Pose& pose) const {
    const auto rotation = rotation_matrix(pose.rotation);
    double magnitude = object_radius_;
    for (int a = 0; a < 3; ++a) magnitude += std::fabs(p[a]) + std::fabs(pose.translation[a]);
    for (int a = 0; a < 3; ++a) {
      double local = 0.0;
      for (int r = 0; r < 3; ++r) local += rotation[3 * r + a] * (p[r] - pose.translation[r]);
      if (local < object_local_box_.lo[a] - magnitude * 0x1p-30 ||
          local > object_local_box_.hi[a] + magnitude * 0x1p-30)
        return false;
    }
    return true;
  }

  // A closed object component with its points placed by apply_pose, as the triangle tests
  // place them (orient_polygon_soup's duplicates carry the same coordinates).
  static Mesh place_mesh(const Mesh& local, const Pose& pose) {
    const auto rotation = rotation_matrix(pose.rotation);
    Mesh placed = local;
    for (const auto v : placed.vertices())
      placed.point(v) = to_point(apply_pose(rotation, pose.translation, to_vec3(local.point(v))));
    return placed;
  }

  bool surfaces_touch(const std::vector<Point>& placed,
                      const std::vector<Tree::Primitive_id>& candidates) const {
    CGAL::Bbox_3 candidates_box;
    std::vector<std::pair<CGAL::Bbox_3, const Triangle*>> near;
    near.reserve(candidates.size());
    for (const auto& id : candidates) {
      const Triangle& t = *id;
      near.emplace_back(t.bbox(), &t);
      candidates_box += t.bbox();
    }
    for (const auto& tri : object_triangles_) {
      const Triangle placed_triangle(placed[tri[0]], placed[tri[1]], placed[tri[2]]);
      const CGAL::Bbox_3 box = placed_triangle.bbox();
      if (!CGAL::do_overlap(box, candidates_box)) continue;
      for (const auto& [candidate_box, candidate] : near) {
        if (!CGAL::do_overlap(box, candidate_box)) continue;
        if (CGAL::do_intersect(placed_triangle, *candidate)) return true;
      }
    }
    return false;
  }

  std::vector<Triangle> environment_triangles_;
  Tree environment_tree_;
  BoundingBox environment_bounds_;
  std::vector<std::uint32_t> environment_component_;  // per environment triangle
  std::vector<EnvironmentComponent> environment_components_;
  std::vector<std::unique_ptr<Solid>> solids_;  // the closed environment components
  SolidBoxTree solid_boxes_;                    // their boxes; ids index solids_
  std::vector<Vec3> object_vertices_;
  std::vector<TriangleIndices> object_triangles_;
  std::vector<std::uint32_t> object_representatives_;  // one vertex per object component
  std::vector<Mesh> object_closed_;                    // closed object components, own frame
  BoundingBox object_local_box_;                       // the object's vertices in its own frame
  double object_radius_ = 0.0;
};

ReferenceCollider::ReferenceCollider(const TriangleSoup& environment, const TriangleSoup& object)
    : impl_(std::make_unique<Impl>(environment, object)) {}
ReferenceCollider::~ReferenceCollider() = default;
ReferenceCollider::ReferenceCollider(ReferenceCollider&&) noexcept = default;
ReferenceCollider& ReferenceCollider::operator=(ReferenceCollider&&) noexcept = default;

ReferenceCollider::Answer ReferenceCollider::query(const Pose& pose) const {
  return impl_->query(pose);
}
bool ReferenceCollider::surfaces_touch(const Pose& pose) const {
  return impl_->surfaces_touch(pose);
}
bool ReferenceCollider::inside_environment(const Vec3& p) const {
  return impl_->inside(to_point(p));
}
BoundingBox ReferenceCollider::object_bounds(const Pose& pose) const {
  return impl_->object_bounds(pose);
}
const BoundingBox& ReferenceCollider::environment_bounds() const {
  return impl_->environment_bounds();
}
double ReferenceCollider::object_radius() const {
  return impl_->object_radius();
}
std::size_t ReferenceCollider::environment_components() const {
  return impl_->environment_components();
}
std::size_t ReferenceCollider::environment_closed_components() const {
  return impl_->environment_closed_components();
}
std::size_t ReferenceCollider::object_components() const {
  return impl_->object_components();
}
std::size_t ReferenceCollider::object_closed_components() const {
  return impl_->object_closed_components();
}

}  // namespace tetrapage
