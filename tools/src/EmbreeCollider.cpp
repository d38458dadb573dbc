#include "tetrapage/tools/EmbreeCollider.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include <atomic>
#include <climits>
#include <cmath>
#include <exception>
#include <limits>
#include <mutex>
#include <string>
#include <vector>

#include "tetrapage/formats/Error.h"
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

// The triangles of one user geometry, as its callbacks and the pair test read them.
struct TriangleSet {
  std::vector<Triangle> triangles;
  std::vector<CGAL::Bbox_3> boxes;     // exact double boxes of the corners
  std::vector<RTCBounds> float_boxes;  // the same, rounded outward, as Embree gets them

  void resize(std::size_t n) {
    triangles.resize(n);
    boxes.resize(n);
    float_boxes.resize(n);
  }

  void set(std::size_t t, const Point& a, const Point& b, const Point& c) {
    triangles[t] = Triangle(a, b, c);
    const CGAL::Bbox_3 box(std::min({a.x(), b.x(), c.x()}), std::min({a.y(), b.y(), c.y()}),
                           std::min({a.z(), b.z(), c.z()}), std::max({a.x(), b.x(), c.x()}),
                           std::max({a.y(), b.y(), c.y()}), std::max({a.z(), b.z(), c.z()}));
    boxes[t] = box;
    RTCBounds& f = float_boxes[t];
    f = RTCBounds{};
    f.lower_x = float_below(box.xmin());
    f.lower_y = float_below(box.ymin());
    f.lower_z = float_below(box.zmin());
    f.upper_x = float_above(box.xmax());
    f.upper_y = float_above(box.ymax());
    f.upper_z = float_above(box.zmax());
  }
};

void report_bounds(const RTCBoundsFunctionArguments* args) {
  const auto* set = static_cast<const TriangleSet*>(args->geometryUserPtr);
  *args->bounds_o = set->float_boxes[args->primID];
}

// What the collide callback accumulates; Embree calls it from its worker threads.
struct PairDecisions {
  const TriangleSet* environment = nullptr;  // scene 0 of rtcCollide
  const TriangleSet* object = nullptr;       // scene 1
  std::atomic<std::uint64_t> candidates{0}, tests{0}, touching{0};
  std::mutex failure_mutex;
  std::exception_ptr failure;  // an exception must not cross Embree's C frames

  static void decide(void* self, RTCCollision* collisions, unsigned int count) {
    auto* state = static_cast<PairDecisions*>(self);
    try {
      std::uint64_t tests = 0, touching = 0;
      for (unsigned int i = 0; i < count; ++i) {
        const unsigned int e = collisions[i].primID0, o = collisions[i].primID1;
        // Embree reports every pair of two overlapping leaves; most boxes are apart.
        if (!CGAL::do_overlap(state->environment->boxes[e], state->object->boxes[o])) continue;
        ++tests;
        if (CGAL::do_intersect(state->environment->triangles[e], state->object->triangles[o])) ++touching;
      }
      state->candidates += count;
      state->tests += tests;
      state->touching += touching;
    } catch (...) {
      const std::lock_guard lock(state->failure_mutex);
      if (!state->failure) state->failure = std::current_exception();
    }
  }
};

void check_range(const Vec3& v, const std::string& what) {
  for (int a = 0; a < 3; ++a)
    if (!(std::abs(v[a]) < kEmbreeRange))
      throw InputError("Embree collider: " + what + " has coordinate " + std::to_string(v[a]) +
                       ", beyond the range Embree's float boxes hold (|x| < 1e18)");
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

    environment_.resize(environment.triangles.size());
    for (std::size_t t = 0; t < environment.triangles.size(); ++t) {
      const auto c = environment.corners(t);
      for (const auto& v : c) check_range(v, "environment triangle " + std::to_string(t));
      environment_.set(t, to_point(c[0]), to_point(c[1]), to_point(c[2]));
    }
    environment_scene_ = device_.new_scene(RTC_SCENE_FLAG_NONE, RTC_BUILD_QUALITY_MEDIUM);
    attach_user_geometry(environment_scene_.get(), environment_);  // the scene holds it
    rtcCommitScene(environment_scene_.get());
    device_.check("committing the environment's scene");

    object_vertices_ = object.vertices;
    object_triangles_ = object.triangles;
    object_.resize(object_triangles_.size());
    placed_.resize(object_vertices_.size());
    // Rebuilt from scratch for every pose: a dynamic scene with the fastest build.
    object_scene_ = device_.new_scene(RTC_SCENE_FLAG_DYNAMIC, RTC_BUILD_QUALITY_LOW);
    object_geometry_ = attach_user_geometry(object_scene_.get(), object_);
  }

  Answer query(const Pose& pose) {
    const auto rotation = rotation_matrix(pose.rotation);
    for (std::size_t v = 0; v < object_vertices_.size(); ++v) {
      const Vec3 w = apply_pose(rotation, pose.translation, object_vertices_[v]);
      check_range(w, "the placed object's vertex " + std::to_string(v));
      placed_[v] = to_point(w);
    }
    for (std::size_t t = 0; t < object_triangles_.size(); ++t) {
      const auto& tri = object_triangles_[t];
      object_.set(t, placed_[tri[0]], placed_[tri[1]], placed_[tri[2]]);
    }
    rtcCommitGeometry(object_geometry_.get());  // its primitives' boxes changed
    rtcCommitScene(object_scene_.get());
    device_.check("committing the object's scene");

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
  // One user geometry whose primitives are `set`'s triangles; rtcCollide needs nothing else
  // of it (no intersect or occluded callback: no ray is ever shot at these scenes).
  EmbreeGeometry attach_user_geometry(RTCScene scene, TriangleSet& set) {
    EmbreeGeometry geometry = device_.new_geometry(RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(geometry.get(), static_cast<unsigned int>(set.triangles.size()));
    rtcSetGeometryUserData(geometry.get(), &set);
    rtcSetGeometryBoundsFunction(geometry.get(), &report_bounds, &set);
    rtcCommitGeometry(geometry.get());
    rtcAttachGeometry(scene, geometry.get());
    device_.check("creating a user geometry");
    return geometry;
  }

  EmbreeDevice device_;  // first in, last out: every scene and geometry goes before it
  TriangleSet environment_, object_;
  EmbreeScene environment_scene_, object_scene_;
  EmbreeGeometry object_geometry_;
  std::vector<Vec3> object_vertices_;
  std::vector<TriangleIndices> object_triangles_;
  std::vector<Point> placed_;
};

EmbreeCollider::EmbreeCollider(const TriangleSoup& environment, const TriangleSoup& object, unsigned threads)
    : impl_(std::make_unique<Impl>(environment, object, threads)) {}
EmbreeCollider::~EmbreeCollider() = default;
EmbreeCollider::EmbreeCollider(EmbreeCollider&&) noexcept = default;
EmbreeCollider& EmbreeCollider::operator=(EmbreeCollider&&) noexcept = default;

EmbreeCollider::Answer EmbreeCollider::query(const Pose& pose) { return impl_->query(pose); }

}  // namespace tetrapage
