#include "tetrapage/tools/EmbreeCollider.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <climits>
#include <cmath>
#include <exception>
#include <limits>
#include <mutex>
#include <string>
#include <vector>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/tools/EmbreeHandles.h"

namespace tetrapage {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;

// Embree drops a primitive whose box reaches its "infinity" (about 1.8e18 in float); stay
// well inside it and say so rather than lose triangles silently.
constexpr double kEmbreeRange = 1e18;

float float_below(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) > x) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}

float float_above(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) < x) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

CGAL::Bbox_3 box_of(const Point& a, const Point& b, const Point& c) {
  return CGAL::Bbox_3(std::min({a.x(), b.x(), c.x()}), std::min({a.y(), b.y(), c.y()}),
                      std::min({a.z(), b.z(), c.z()}), std::max({a.x(), b.x(), c.x()}),
                      std::max({a.y(), b.y(), c.y()}), std::max({a.z(), b.z(), c.z()}));
}

// The environment's triangles, fixed: what its bounds callback and the pair test read.
struct EnvironmentTriangles {
  std::vector<Triangle> triangles;
  std::vector<CGAL::Bbox_3> boxes;  // exact double boxes of the corners

  static void report_bounds(const RTCBoundsFunctionArguments* args) {
    const auto* self = static_cast<const EnvironmentTriangles*>(args->geometryUserPtr);
    const CGAL::Bbox_3& box = self->boxes[args->primID];
    RTCBounds& out = *args->bounds_o;
    out.lower_x = float_below(box.xmin());
    out.lower_y = float_below(box.ymin());
    out.lower_z = float_below(box.zmin());
    out.upper_x = float_above(box.xmax());
    out.upper_y = float_above(box.ymax());
    out.upper_z = float_above(box.zmax());
  }
};

// The object's triangles at the current pose. Vertices are rounded once per pose: rounding
// is monotone, so the min of the rounded-down corners is the rounded-down min.
struct PlacedObject {
  std::vector<TriangleIndices> triangles;
  std::vector<Point> placed;                       // apply_pose() of each vertex, in double
  std::vector<std::array<float, 3>> below, above;  // each placed vertex rounded down / up

  Triangle triangle(unsigned int t) const {
    const auto& i = triangles[t];
    return Triangle(placed[i[0]], placed[i[1]], placed[i[2]]);
  }
  CGAL::Bbox_3 box(unsigned int t) const {
    const auto& i = triangles[t];
    return box_of(placed[i[0]], placed[i[1]], placed[i[2]]);
  }

  static void report_bounds(const RTCBoundsFunctionArguments* args) {
    const auto* self = static_cast<const PlacedObject*>(args->geometryUserPtr);
    const auto& i = self->triangles[args->primID];
    const auto& b0 = self->below[i[0]], &b1 = self->below[i[1]], &b2 = self->below[i[2]];
    const auto& a0 = self->above[i[0]], &a1 = self->above[i[1]], &a2 = self->above[i[2]];
    RTCBounds& out = *args->bounds_o;
    out.lower_x = std::min({b0[0], b1[0], b2[0]});
    out.lower_y = std::min({b0[1], b1[1], b2[1]});
    out.lower_z = std::min({b0[2], b1[2], b2[2]});
    out.upper_x = std::max({a0[0], a1[0], a2[0]});
    out.upper_y = std::max({a0[1], a1[1], a2[1]});
    out.upper_z = std::max({a0[2], a1[2], a2[2]});
  }
};

// What the collide callback accumulates; Embree calls it from its worker threads.
struct PairDecisions {
  const EnvironmentTriangles* environment = nullptr;  // scene 0 of rtcCollide
  const PlacedObject* object = nullptr;               // scene 1
  std::atomic<std::uint64_t> candidates{0}, tests{0}, touching{0};
  std::mutex failure_mutex;
  std::exception_ptr failure;  // an exception must not cross Embree's C frames

  static void decide(void* user, RTCCollision* collisions, unsigned int count) {
    auto* self = static_cast<PairDecisions*>(user);
    try {
      std::uint64_t tests = 0, touching = 0;
      for (unsigned int i = 0; i < count; ++i) {
        const unsigned int e = collisions[i].primID0, o = collisions[i].primID1;
        // Embree reports every pair of two overlapping leaves; most boxes are apart.
        if (!CGAL::do_overlap(self->environment->boxes[e], self->object->box(o))) continue;
        ++tests;
        if (CGAL::do_intersect(self->environment->triangles[e], self->object->triangle(o))) ++touching;
      }
      self->candidates += count;
      self->tests += tests;
      self->touching += touching;
    } catch (...) {
      const std::lock_guard lock(self->failure_mutex);
      if (!self->failure) self->failure = std::current_exception();
    }
  }
};

bool in_embree_range(const Vec3& v) {
  return std::abs(v[0]) < kEmbreeRange && std::abs(v[1]) < kEmbreeRange && std::abs(v[2]) < kEmbreeRange;
}

[[noreturn]] void throw_out_of_range(const Vec3& v, const std::string& what) {
  throw InputError("Embree collider: " + what + " is at (" + std::to_string(v[0]) + ", " +
                   std::to_string(v[1]) + ", " + std::to_string(v[2]) +
                   "), beyond the range Embree's float boxes hold (|x| < 1e18)");
}

Point to_point(const Vec3& v) { return Point(v[0], v[1], v[2]); }

}  // namespace

class EmbreeCollider::Impl {
 public:
  Impl(const TriangleSoup& environment, const TriangleSoup& object, unsigned threads) : device_(threads) {
    if (environment.triangles.empty()) throw InputError("Embree collider: the environment has no triangle");
    if (object.triangles.empty()) throw InputError("Embree collider: the object has no triangle");
    if (environment.triangles.size() > UINT_MAX || object.triangles.size() > UINT_MAX)
      throw InputError("Embree collider: more than 2^32 - 1 triangles in one geometry");

    environment_.triangles.reserve(environment.triangles.size());
    environment_.boxes.reserve(environment.triangles.size());
    for (std::size_t t = 0; t < environment.triangles.size(); ++t) {
      const auto c = environment.corners(t);
      for (const auto& v : c)
        if (!in_embree_range(v)) throw_out_of_range(v, "a corner of environment triangle " + std::to_string(t));
      const Point a = to_point(c[0]), b = to_point(c[1]), d = to_point(c[2]);
      environment_.triangles.emplace_back(a, b, d);
      environment_.boxes.push_back(box_of(a, b, d));
    }
    environment_scene_ = device_.new_scene(RTC_SCENE_FLAG_NONE, RTC_BUILD_QUALITY_MEDIUM);
    attach_user_geometry(environment_scene_.get(), environment_.triangles.size(),
                         &EnvironmentTriangles::report_bounds, &environment_);  // the scene holds it
    rtcCommitScene(environment_scene_.get());
    device_.check("committing the environment's scene");

    object_vertices_ = object.vertices;
    object_.triangles = object.triangles;
    object_.placed.resize(object_vertices_.size());
    object_.below.resize(object_vertices_.size());
    object_.above.resize(object_vertices_.size());
    // The object's tree is built once, in its own frame, and only refitted to each pose (a
    // full rebuild of 2,000 user primitives costs ~0.5 ms, a refit ~20 us). A refitted box
    // still bounds its children, so the candidates stay a superset of the touching pairs.
    object_scene_ = device_.new_scene(RTC_SCENE_FLAG_DYNAMIC, RTC_BUILD_QUALITY_LOW);
    object_geometry_ = attach_user_geometry(object_scene_.get(), object_.triangles.size(),
                                            &PlacedObject::report_bounds, &object_);
    rtcSetGeometryBuildQuality(object_geometry_.get(), RTC_BUILD_QUALITY_REFIT);
    device_.check("asking for refits of the object's tree");
    place_object(Pose{});
  }

  Answer query(const Pose& pose) {
    place_object(pose);

    PairDecisions decisions;
    decisions.environment = &environment_;
    decisions.object = &object_;
    rtcCollide(environment_scene_.get(), object_scene_.get(), &PairDecisions::decide, &decisions);
    device_.check("rtcCollide");
    if (decisions.failure) std::rethrow_exception(decisions.failure);

    Answer answer;
    answer.candidate_pairs = decisions.candidates;
    answer.exact_tests = decisions.tests;
    answer.touching_pairs = decisions.touching;
    answer.surfaces_touch = answer.touching_pairs > 0;
    return answer;
  }

 private:
  // Places the object's vertices at `pose` and refits its tree.
  void place_object(const Pose& pose) {
    const auto rotation = rotation_matrix(pose.rotation);
    for (std::size_t v = 0; v < object_vertices_.size(); ++v) {
      const Vec3 w = apply_pose(rotation, pose.translation, object_vertices_[v]);
      if (!in_embree_range(w)) throw_out_of_range(w, "the object's vertex " + std::to_string(v) + " placed");
      object_.placed[v] = to_point(w);
      for (int a = 0; a < 3; ++a) {
        object_.below[v][a] = float_below(w[a]);
        object_.above[v][a] = float_above(w[a]);
      }
    }
    rtcCommitGeometry(object_geometry_.get());  // its primitives' boxes changed
    rtcCommitScene(object_scene_.get());
    device_.check("committing the object's scene");
  }

  // One user geometry of `count` primitives whose boxes `bounds` reports from `data`.
  // rtcCollide needs nothing else of it (no intersect or occluded callback: no ray is ever
  // shot at these scenes).
  EmbreeGeometry attach_user_geometry(RTCScene scene, std::size_t count, RTCBoundsFunction bounds, void* data) {
    EmbreeGeometry geometry = device_.new_geometry(RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(geometry.get(), static_cast<unsigned int>(count));
    rtcSetGeometryUserData(geometry.get(), data);
    rtcSetGeometryBoundsFunction(geometry.get(), bounds, data);
    rtcCommitGeometry(geometry.get());
    rtcAttachGeometry(scene, geometry.get());
    device_.check("creating a user geometry");
    return geometry;
  }

  EmbreeDevice device_;  // first in, last out: every scene and geometry goes before it
  EnvironmentTriangles environment_;
  PlacedObject object_;
  std::vector<Vec3> object_vertices_;  // in the object's own frame
  EmbreeScene environment_scene_, object_scene_;
  EmbreeGeometry object_geometry_;
};

EmbreeCollider::EmbreeCollider(const TriangleSoup& environment, const TriangleSoup& object, unsigned threads)
    : impl_(std::make_unique<Impl>(environment, object, threads)) {}
EmbreeCollider::~EmbreeCollider() = default;
EmbreeCollider::EmbreeCollider(EmbreeCollider&&) noexcept = default;
EmbreeCollider& EmbreeCollider::operator=(EmbreeCollider&&) noexcept = default;

EmbreeCollider::Answer EmbreeCollider::query(const Pose& pose) { return impl_->query(pose); }

}  // namespace tetrapage
