#include "tetrapage/tools/ModelRenderer.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/tools/EmbreeHandles.h"

namespace tetrapage {
namespace {

using Colour = std::array<double, 3>;

Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3 add(const Vec3& a, const Vec3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
Vec3 scale(const Vec3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
Vec3 normalised(const Vec3& a) { return scale(a, 1.0 / std::sqrt(dot(a, a))); }

// A well-mixed number in [0, 1) per region, so that neighbouring regions differ.
double hash01(std::uint32_t x) {
  std::uint64_t h = x * 0x9E3779B97F4A7C15ull;
  h ^= h >> 31;
  h *= 0xBF58476D1CE4E5B9ull;
  h ^= h >> 29;
  return double(h >> 11) / double(std::uint64_t(1) << 53);
}

Colour hsv(double h, double s, double v) {
  const double c = v * s, x = c * (1 - std::fabs(std::fmod(h * 6, 2) - 1)), m = v - c;
  const int sector = int(h * 6) % 6;
  const std::array<Colour, 6> table{{{c, x, 0}, {x, c, 0}, {0, c, x}, {0, x, c}, {x, 0, c}, {c, 0, x}}};
  const Colour& t = table[std::size_t(sector)];
  return {t[0] + m, t[1] + m, t[2] + m};
}

struct Camera {
  Vec3 eye, forward, right, up;
  double tan_half_fov, aspect;
  std::size_t width, height;

  Vec3 ray(double px, double py) const {
    const double x = (2 * px / double(width) - 1) * tan_half_fov * aspect;
    const double y = (1 - 2 * py / double(height)) * tan_half_fov;
    return add(forward, add(scale(right, x), scale(up, y)));
  }
  // Pixel coordinates and distance of a point in front of the camera.
  bool project(const Vec3& p, double& px, double& py, double& distance) const {
    const Vec3 q = sub(p, eye);
    const double z = dot(q, forward);
    if (z <= 1e-12) return false;
    px = (dot(q, right) / (z * tan_half_fov * aspect) + 1) * 0.5 * double(width);
    py = (1 - dot(q, up) / (z * tan_half_fov)) * 0.5 * double(height);
    distance = std::sqrt(dot(q, q));
    return true;
  }
};

}  // namespace

RgbImage render_model(const CollisionIndex& index, const RenderOptions& options, RenderSummary& summary) {
  const auto start = std::chrono::steady_clock::now();
  if (options.width == 0 || options.height == 0 || options.width > 16384 || options.height > 16384)
    throw InputError("render: image size " + std::to_string(options.width) + "x" + std::to_string(options.height) +
                     " (each side must be 1..16384)");
  const std::uint32_t shards = index.shard_count();
  if (options.colouring == RenderColouring::page_ins && options.page_ins.size() != shards)
    throw InputError("render: " + std::to_string(options.page_ins.size()) + " page-in counts for " +
                     std::to_string(shards) + " shards of " + index.path().string());
  summary = {};
  summary.shards = shards;
  const std::uint64_t input = std::max<std::uint64_t>(index.header().input_triangles, 1);
  summary.stride = std::max<std::uint64_t>(1, (input + options.max_triangles - 1) / std::max<std::uint64_t>(options.max_triangles, 1));

  // The triangles, each once (the first shard that holds it colours it), relative to the
  // model's centre so that float keeps the detail.
  // The box of the stored triangles (the coarse mesh's own box is enlarged around them).
  BoundingBox bounds;
  for (std::uint32_t s = 0; s < shards; ++s) bounds.extend(index.shard_bounds(s));
  if (bounds.empty()) bounds = index.mesh_bounds();
  const Vec3 centre = bounds.center();
  std::vector<float> vertices;
  std::vector<std::uint32_t> shard_of_primitive;
  std::vector<std::uint64_t> seen((input + 63) / 64, 0);
  std::vector<ShardKind> kinds(shards);
  for (std::uint32_t s = 0; s < shards; ++s) {
    const auto pin = index.cache().acquire(s);
    kinds[s] = pin->kind();
    for (std::uint32_t local = 0; local < pin->triangle_count(); ++local) {
      const std::uint64_t id = pin->triangle_id(local);
      if (id < input) {
        if (seen[id / 64] >> (id % 64) & 1) continue;
        seen[id / 64] |= std::uint64_t(1) << (id % 64);
      }
      if (id % summary.stride != 0) continue;
      for (const auto& p : pin->triangle(local))
        for (int a = 0; a < 3; ++a) vertices.push_back(float(p[a] - centre[a]));
      shard_of_primitive.push_back(s);
    }
  }
  summary.triangles_drawn = shard_of_primitive.size();

  // Per-shard colours.
  std::vector<Colour> colours(shards);
  std::uint32_t most = 1;
  for (const auto n : options.page_ins) most = std::max(most, n);
  for (std::uint32_t s = 0; s < shards; ++s) {
    const double shade = 0.75 + 0.35 * hash01(s);
    switch (options.colouring) {
      case RenderColouring::shard_kind: {
        const Colour base = kinds[s] == ShardKind::grid ? Colour{0.30, 0.58, 0.82} : Colour{0.93, 0.56, 0.22};
        colours[s] = {base[0] * shade, base[1] * shade, base[2] * shade};
        break;
      }
      case RenderColouring::regions: colours[s] = hsv(hash01(s), 0.55, 0.95); break;
      case RenderColouring::page_ins: {
        const std::uint32_t n = options.page_ins[s];
        if (n == 0) {
          colours[s] = {0.78 * shade, 0.78 * shade, 0.78 * shade};
        } else {
          const double t = std::log1p(double(n)) / std::log1p(double(most));
          colours[s] = {1.0 - 0.2 * t, 0.9 * (1 - t) + 0.1 * t, 0.3 * (1 - t)};
        }
        break;
      }
    }
  }

  EmbreeDevice device;
  EmbreeScene scene = device.new_scene(RTC_SCENE_FLAG_NONE, RTC_BUILD_QUALITY_LOW);
  const std::size_t n = shard_of_primitive.size();
  if (n > 0) {
    EmbreeGeometry geometry = device.new_geometry(RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetSharedGeometryBuffer(geometry.get(), RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, vertices.data(), 0,
                               3 * sizeof(float), 3 * n);
    auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geometry.get(), RTC_BUFFER_TYPE_INDEX, 0,
                                                                   RTC_FORMAT_UINT3, 3 * sizeof(unsigned), n));
    device.check("allocating the index buffer of " + std::to_string(n) + " triangles");
    for (std::size_t k = 0; k < 3 * n; ++k) indices[k] = unsigned(k);
    rtcCommitGeometry(geometry.get());
    rtcAttachGeometry(scene.get(), geometry.get());
  }
  rtcCommitScene(scene.get());
  device.check("building the scene of " + std::to_string(n) + " triangles");

  // The camera looks at the centre from outside the model's bounding sphere.
  const double degrees = std::numbers::pi / 180;
  const double az = options.azimuth_degrees * degrees, el = options.elevation_degrees * degrees;
  const Vec3 towards_camera{std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
  const double radius = 0.5 * std::sqrt(dot(bounds.size(), bounds.size()));
  Camera camera;
  camera.width = options.width;
  camera.height = options.height;
  camera.tan_half_fov = std::tan(20 * degrees);
  camera.aspect = double(options.width) / double(options.height);
  const double distance = radius / std::sin(20 * degrees) / std::max(options.zoom, 1e-3);
  camera.eye = scale(towards_camera, distance);  // relative to the centre
  camera.forward = scale(towards_camera, -1);
  const Vec3 world_up = std::fabs(towards_camera[2]) > 0.999 ? Vec3{0, 1, 0} : Vec3{0, 0, 1};
  camera.right = normalised(cross(camera.forward, world_up));
  camera.up = cross(camera.right, camera.forward);

  RgbImage image(options.width, options.height);
  std::vector<float> depth(options.width * options.height, std::numeric_limits<float>::infinity());
  std::vector<std::uint64_t> row_hits(options.height, 0);
  tbb::parallel_for(std::size_t(0), options.height, [&](std::size_t y) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (std::size_t x = 0; x < options.width; ++x) {
      const Vec3 d = camera.ray(double(x) + 0.5, double(y) + 0.5);
      RTCRayHit query{};
      query.ray.org_x = float(camera.eye[0]);
      query.ray.org_y = float(camera.eye[1]);
      query.ray.org_z = float(camera.eye[2]);
      query.ray.dir_x = float(d[0]);
      query.ray.dir_y = float(d[1]);
      query.ray.dir_z = float(d[2]);
      query.ray.tnear = 0;
      query.ray.tfar = std::numeric_limits<float>::infinity();
      query.ray.mask = 0xffffffffu;
      query.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(scene.get(), &context, &query);
      std::uint8_t* pixel = image.at(x, y);
      if (query.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
        const double t = double(y) / double(options.height);
        const Colour sky{0.97 - 0.12 * t, 0.97 - 0.10 * t, 0.99 - 0.06 * t};
        for (int c = 0; c < 3; ++c) pixel[c] = std::uint8_t(255 * sky[c]);
        continue;
      }
      ++row_hits[y];
      const Vec3 normal = normalised({query.hit.Ng_x, query.hit.Ng_y, query.hit.Ng_z});
      const double facing = std::fabs(dot(normal, normalised(d)));
      const double light = 0.28 + 0.72 * facing;
      const Colour& base = colours[shard_of_primitive[query.hit.primID]];
      for (int c = 0; c < 3; ++c) pixel[c] = std::uint8_t(std::clamp(255 * base[c] * light, 0.0, 255.0));
      depth[y * options.width + x] = float(query.ray.tfar * std::sqrt(dot(d, d)));
    }
  });
  for (const auto h : row_hits) summary.pixels_hit += h;

  // The flight path: magenta where visible, faint where the model is in front of it.
  auto blend = [&](long x, long y, double dist, bool endpoint, const Colour& colour) {
    for (long dy = -1; dy <= 1; ++dy)
      for (long dx = -1; dx <= 1; ++dx) {
        if (!endpoint && (dx != 0 && dy != 0)) continue;
        const long px = x + dx, py = y + dy;
        if (px < 0 || py < 0 || px >= long(options.width) || py >= long(options.height)) continue;
        const bool hidden = dist > double(depth[std::size_t(py) * options.width + std::size_t(px)]) * 1.0005;
        const double alpha = hidden ? 0.25 : 1.0;
        std::uint8_t* pixel = image.at(std::size_t(px), std::size_t(py));
        for (int c = 0; c < 3; ++c) pixel[c] = std::uint8_t((1 - alpha) * pixel[c] + alpha * 255 * colour[c]);
      }
  };
  const Colour path_colour{0.85, 0.05, 0.65};
  for (std::size_t i = 0; i + 1 < options.path.size(); ++i) {
    const Vec3 a = sub(options.path[i], centre), b = sub(options.path[i + 1], centre);
    double ax, ay, ad, bx, by, bd;
    if (!camera.project(a, ax, ay, ad) || !camera.project(b, bx, by, bd)) continue;
    const int samples = std::max(1, int(std::ceil(std::max(std::fabs(bx - ax), std::fabs(by - ay)))));
    for (int k = 0; k <= samples; ++k) {
      const double t = double(k) / samples;
      double px, py, pd;
      if (!camera.project(add(a, scale(sub(b, a), t)), px, py, pd)) continue;
      blend(long(px), long(py), pd, false, path_colour);
    }
  }
  if (!options.path.empty()) {
    double px, py, pd;
    if (camera.project(sub(options.path.front(), centre), px, py, pd)) blend(long(px), long(py), pd, true, {0.1, 0.7, 0.2});
    if (camera.project(sub(options.path.back(), centre), px, py, pd)) blend(long(px), long(py), pd, true, {0.9, 0.1, 0.1});
  }
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return image;
}

}  // namespace tetrapage
