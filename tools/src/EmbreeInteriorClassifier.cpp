#include "tetrapage/tools/EmbreeInteriorClassifier.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/tools/EmbreeHandles.h"

namespace tetrapage {
namespace {

// Directions with no rational relation to the axes or to each other, so that rays from
// generated points almost never graze an edge of an axis-aligned model.
constexpr std::array<std::array<float, 3>, 5> kDirections{{{0.0123457f, 0.0345679f, 1.0f},
                                                           {0.9134f, -0.2718f, 0.3011f},
                                                           {-0.3141f, 0.8660f, -0.3890f},
                                                           {-0.5772f, -0.6931f, 0.4142f},
                                                           {0.2236f, 0.1414f, -0.9643f}}};

// Every hit along one ray: the filter records the primitive and rejects the hit, so that
// traversal goes on to the next one.
struct CountingContext {
  RTCIntersectContext context;  // first: Embree hands the filter a pointer to it
  std::vector<std::uint32_t>* primitives;
};

void record_hit(const RTCFilterFunctionNArguments* args) {
  auto* counting = reinterpret_cast<CountingContext*>(args->context);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] == 0) continue;
    counting->primitives->push_back(RTCHitN_primID(args->hit, args->N, i));
    args->valid[i] = 0;
  }
}

}  // namespace

class EmbreeInteriorClassifier::Impl {
 public:
  explicit Impl(unsigned rays) : rays_(std::clamp(rays, 2u, unsigned(kDirections.size()))) {}

  void add(std::uint32_t part, std::span<const std::array<Vec3, 3>> triangles) {
    for (const auto& t : triangles) {
      triangles_.push_back(t);
      part_of_.push_back(part);
      for (const auto& p : t) bounds_.extend(p);
    }
  }

  void classify(std::span<const Vec3> points, std::vector<PointInterior>& out) {
    out.assign(points.size(), PointInterior{});
    if (triangles_.empty()) return;
    build();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 64),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        std::vector<std::uint32_t> hits, odd;
                        std::vector<std::vector<std::uint32_t>> answers(rays_);
                        for (std::size_t i = range.begin(); i < range.end(); ++i) {
                          for (unsigned r = 0; r < rays_; ++r) {
                            odd_parts(points[i], kDirections[r], hits, odd);
                            answers[r] = odd;
                          }
                          // The parts are closed, so only a ray through an edge or a vertex (or
                          // a point within float precision of a surface) can be wrong: decided
                          // when every ray agrees (preprocess moves an undecided point and asks
                          // again).
                          bool decided = true;
                          for (unsigned q = 1; q < rays_; ++q) decided = decided && answers[q] == answers[0];
                          if (decided) out[i].parts = answers[0];
                          out[i].decided = decided;
                        }
                      });
  }

 private:
  void build() {
    device_ = std::make_unique<EmbreeDevice>();
    // No spatial splits: each triangle sits in one leaf, so a ray meets it at most once.
    scene_ = device_->new_scene(RTC_SCENE_FLAG_ROBUST, RTC_BUILD_QUALITY_MEDIUM);
    EmbreeGeometry geometry = device_->new_geometry(RTC_GEOMETRY_TYPE_TRIANGLE);
    const std::size_t n = triangles_.size();
    centre_ = bounds_.center();
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
        geometry.get(), RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 3 * n));
    auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        geometry.get(), RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), n));
    device_->check("allocating the buffers of " + std::to_string(n) + " closed-part triangles");
    for (std::size_t t = 0; t < n; ++t)
      for (int k = 0; k < 3; ++k) {
        for (int a = 0; a < 3; ++a)
          vertices[9 * t + 3 * k + a] = float(triangles_[t][k][a] - centre_[a]);
        indices[3 * t + k] = unsigned(3 * t + k);
      }
    std::vector<std::array<Vec3, 3>>().swap(triangles_);  // Embree holds them now
    rtcSetGeometryIntersectFilterFunction(geometry.get(), record_hit);
    rtcCommitGeometry(geometry.get());
    rtcAttachGeometry(scene_.get(), geometry.get());
    rtcCommitScene(scene_.get());
    device_->check("building the scene of " + std::to_string(n) + " closed-part triangles");
  }

  // The parts crossed an odd number of times by the ray from p along `direction`, sorted.
  void odd_parts(const Vec3& p, const std::array<float, 3>& direction,
                 std::vector<std::uint32_t>& hits, std::vector<std::uint32_t>& odd) const {
    hits.clear();
    CountingContext counting{};
    rtcInitIntersectContext(&counting.context);
    counting.primitives = &hits;
    RTCRayHit query{};
    query.ray.org_x = float(p[0] - centre_[0]);
    query.ray.org_y = float(p[1] - centre_[1]);
    query.ray.org_z = float(p[2] - centre_[2]);
    query.ray.dir_x = direction[0];
    query.ray.dir_y = direction[1];
    query.ray.dir_z = direction[2];
    query.ray.tnear = 0.0f;
    query.ray.tfar = std::numeric_limits<float>::infinity();
    query.ray.mask = 0xffffffffu;
    query.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene_.get(), &counting.context, &query);
    std::sort(hits.begin(), hits.end());
    hits.erase(std::unique(hits.begin(), hits.end()), hits.end());
    odd.clear();
    for (const std::uint32_t primitive : hits) odd.push_back(part_of_[primitive]);
    std::sort(odd.begin(), odd.end());
    // Keep the parts that occur an odd number of times, once each.
    std::size_t kept = 0;
    for (std::size_t i = 0; i < odd.size();) {
      std::size_t j = i;
      while (j < odd.size() && odd[j] == odd[i]) ++j;
      if ((j - i) % 2 == 1) odd[kept++] = odd[i];
      i = j;
    }
    odd.resize(kept);
  }

  unsigned rays_;
  std::vector<std::array<Vec3, 3>> triangles_;
  std::vector<std::uint32_t> part_of_;
  BoundingBox bounds_;
  Vec3 centre_{};
  // The scene is declared after the device, so it is released first.
  std::unique_ptr<EmbreeDevice> device_;
  EmbreeScene scene_;
};

EmbreeInteriorClassifier::EmbreeInteriorClassifier(unsigned rays)
    : impl_(std::make_unique<Impl>(rays)) {}
EmbreeInteriorClassifier::~EmbreeInteriorClassifier() = default;

void EmbreeInteriorClassifier::add_triangles(std::uint32_t part,
                                             std::span<const std::array<Vec3, 3>> triangles) {
  impl_->add(part, triangles);
}

void EmbreeInteriorClassifier::classify(std::span<const Vec3> points,
                                        std::vector<PointInterior>& out) {
  impl_->classify(points, out);
}

}  // namespace tetrapage
