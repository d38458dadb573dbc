#include "tetrapage/tools/EmbreeMeshFaces.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/runtime/geometry/PointTetrahedron.h"
#include "tetrapage/tools/EmbreeHandles.h"

namespace tetrapage {
namespace {

constexpr std::uint32_t kOutside = TetMesh::no_neighbour;

// The filter sees the context Embree was given; the hits travel in the same object.
struct HitCollector {
  RTCIntersectContext context;  // first member: the filter casts the context back
  std::vector<FaceHit>* hits;
};

// Records every hit and rejects it, so that traversal goes on to the farther faces. Embree
// hands the filter the hit distance as the ray's tfar.
void collect_hit(const RTCFilterFunctionNArguments* args) {
  auto* collector = reinterpret_cast<HitCollector*>(args->context);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] == 0) continue;
    collector->hits->push_back(
        {RTCRayN_tfar(args->ray, args->N, i), RTCHitN_primID(args->hit, args->N, i)});
    args->valid[i] = 0;
  }
}

void check_finite(const geometry::Point& p, const char* what) {
  if (!geometry::is_finite(p))
    throw InputError(std::string("Embree mesh faces: ") + what + " (" + std::to_string(p[0]) +
                     ", " + std::to_string(p[1]) + ", " + std::to_string(p[2]) + ") is not finite");
}

bool contains(const std::vector<std::uint32_t>& set, std::uint32_t x) {
  return std::find(set.begin(), set.end(), x) != set.end();
}

void insert(std::vector<std::uint32_t>& set, std::uint32_t x) {
  if (!contains(set, x)) set.push_back(x);
}

}  // namespace

struct EmbreeMeshFaces::Impl {
  const TetMesh* mesh = nullptr;
  std::vector<MeshFace> faces;
  Vec3 centre{0, 0, 0};
  double tie_distance = 0;
  std::optional<EmbreeDevice> device;  // declared before the scene: released after it
  EmbreeScene scene;
};

EmbreeMeshFaces::EmbreeMeshFaces(const TetMesh& mesh, unsigned threads)
    : impl_(std::make_unique<Impl>()) {
  if (mesh.tets.empty()) throw InputError("Embree mesh faces: the mesh has no tet");
  if (mesh.neighbours.size() != mesh.tets.size())
    throw InputError("Embree mesh faces: " + std::to_string(mesh.neighbours.size()) +
                     " neighbour rows for " + std::to_string(mesh.tets.size()) + " tets");
  impl_->mesh = &mesh;
  const std::uint32_t tets = static_cast<std::uint32_t>(mesh.tet_count());
  BoundingBox box;
  for (const auto& v : mesh.vertices) box.extend(v);
  for (std::uint32_t t = 0; t < tets; ++t) {
    for (int k = 0; k < 4; ++k) {
      if (mesh.tets[t][k] >= mesh.vertices.size())
        throw InputError("Embree mesh faces: tet " + std::to_string(t) + " names vertex " +
                         std::to_string(mesh.tets[t][k]) + " of " +
                         std::to_string(mesh.vertices.size()));
      const std::uint32_t n = mesh.neighbours[t][k];
      if (n != kOutside) {
        if (n >= tets || std::find(mesh.neighbours[n].begin(), mesh.neighbours[n].end(), t) ==
                             mesh.neighbours[n].end())
          throw InputError("Embree mesh faces: tets " + std::to_string(t) + " and " +
                           std::to_string(n) + " are not mutual neighbours");
        if (n < t) continue;  // listed once, by the lower tet
      }
      MeshFace face;
      for (int i = 0; i < 3; ++i)
        face.vertices[i] = mesh.tets[t][geometry::kTetrahedronFaces[k][i]];
      face.tet = t;
      face.other = n;
      impl_->faces.push_back(face);
    }
  }
  impl_->centre = box.center();
  const Vec3 size = box.size();
  const double extent = std::max({size[0], size[1], size[2]});
  const double offset = std::max({std::fabs(impl_->centre[0]), std::fabs(impl_->centre[1]),
                                  std::fabs(impl_->centre[2])});
  // About 64 float ulps of the box's extent (coordinates are floats relative to its centre;
  // the centre's own double rounding is the second term): Embree's hit distances are good to
  // a few ulps except at grazing angles, and tets thinner than this are grouped, not missed.
  impl_->tie_distance = std::ldexp(extent, -18) + std::ldexp(offset, -45);

  impl_->device.emplace(threads);
  const EmbreeDevice& device = *impl_->device;
  impl_->scene = device.new_scene(RTC_SCENE_FLAG_ROBUST, RTC_BUILD_QUALITY_MEDIUM);
  const EmbreeGeometry geometry = device.new_geometry(RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
      geometry.get(), RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
      mesh.vertices.size()));
  auto* indices = static_cast<unsigned*>(
      rtcSetNewGeometryBuffer(geometry.get(), RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                              3 * sizeof(unsigned), impl_->faces.size()));
  device.check("rtcSetNewGeometryBuffer");
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v)
    for (int a = 0; a < 3; ++a)
      vertices[3 * v + a] = static_cast<float>(mesh.vertices[v][a] - impl_->centre[a]);
  for (std::size_t f = 0; f < impl_->faces.size(); ++f)
    for (int i = 0; i < 3; ++i) indices[3 * f + i] = impl_->faces[f].vertices[i];
  rtcSetGeometryIntersectFilterFunction(geometry.get(), &collect_hit);
  rtcCommitGeometry(geometry.get());
  rtcAttachGeometry(impl_->scene.get(), geometry.get());
  rtcCommitScene(impl_->scene.get());
  device.check("building the scene of mesh faces");
}

EmbreeMeshFaces::~EmbreeMeshFaces() = default;
EmbreeMeshFaces::EmbreeMeshFaces(EmbreeMeshFaces&&) noexcept = default;
EmbreeMeshFaces& EmbreeMeshFaces::operator=(EmbreeMeshFaces&&) noexcept = default;

const TetMesh& EmbreeMeshFaces::mesh() const { return *impl_->mesh; }
std::span<const MeshFace> EmbreeMeshFaces::faces() const { return impl_->faces; }
double EmbreeMeshFaces::tie_distance() const { return impl_->tie_distance; }

void EmbreeMeshFaces::hits(const geometry::Point& a, const geometry::Point& b,
                           std::vector<FaceHit>& out) const {
  check_finite(a, "segment start");
  check_finite(b, "segment end");
  out.clear();
  RTCRayHit ray{};
  ray.ray.org_x = static_cast<float>(a[0] - impl_->centre[0]);
  ray.ray.org_y = static_cast<float>(a[1] - impl_->centre[1]);
  ray.ray.org_z = static_cast<float>(a[2] - impl_->centre[2]);
  ray.ray.dir_x = static_cast<float>(b[0] - a[0]);
  ray.ray.dir_y = static_cast<float>(b[1] - a[1]);
  ray.ray.dir_z = static_cast<float>(b[2] - a[2]);
  if (ray.ray.dir_x == 0 && ray.ray.dir_y == 0 && ray.ray.dir_z == 0) return;
  ray.ray.tnear = 0;
  ray.ray.tfar = 1;
  ray.ray.mask = ~0u;
  ray.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  ray.hit.primID = RTC_INVALID_GEOMETRY_ID;
  HitCollector collector;
  rtcInitIntersectContext(&collector.context);
  collector.hits = &out;
  rtcIntersect1(impl_->scene.get(), &collector.context, &ray);
  // Each face once (a build may visit a primitive twice), at its nearest report.
  std::sort(out.begin(), out.end(), [](const FaceHit& x, const FaceHit& y) {
    return x.face != y.face ? x.face < y.face : x.t < y.t;
  });
  out.erase(std::unique(out.begin(), out.end(),
                        [](const FaceHit& x, const FaceHit& y) { return x.face == y.face; }),
            out.end());
  std::sort(out.begin(), out.end(), [](const FaceHit& x, const FaceHit& y) {
    return x.t != y.t ? x.t < y.t : x.face < y.face;
  });
}

FaceTrace EmbreeMeshFaces::trace(std::uint32_t start_tet, const geometry::Point& a,
                                 const geometry::Point& b) const {
  if (start_tet >= impl_->mesh->tet_count())
    throw InputError("Embree mesh faces: start tet " + std::to_string(start_tet) +
                     " is out of range (" + std::to_string(impl_->mesh->tet_count()) + " tets)");
  thread_local std::vector<FaceHit> found;
  hits(a, b, found);
  FaceTrace trace;
  trace.faces_hit = static_cast<std::uint32_t>(found.size());
  double length = 0;
  for (int k = 0; k < 3; ++k) length += (b[k] - a[k]) * (b[k] - a[k]);
  length = std::sqrt(length);
  const double tie_t = length > 0 ? impl_->tie_distance / length : 0;

  // `possible`: the tets the segment may be in after the groups so far; `entered`: those the
  // last group stepped into. A group's faces are crossed in any order that steps from a tet
  // already reached, so float noise in the order of near-simultaneous hits does not matter,
  // and a later group keeps only the tets that bound one of its faces.
  std::vector<std::uint32_t> possible{start_tet}, reached, entered{start_tet};
  std::vector<char> used;
  const auto& faces = impl_->faces;
  for (std::size_t begin = 0; begin < found.size();) {
    std::size_t end = begin + 1;
    while (end < found.size() && double(found[end].t) - double(found[end - 1].t) <= tie_t) ++end;
    reached.clear();
    for (std::uint32_t x : possible) {
      if (x == kOutside) continue;
      for (std::size_t h = begin; h < end; ++h)
        if (faces[found[h].face].tet == x || faces[found[h].face].other == x) {
          insert(reached, x);
          break;
        }
    }
    const std::size_t from = reached.size();
    if (reached.empty()) {
      // A face Embree missed before, or a spurious hit: go on from both sides of this group.
      ++trace.resyncs;
      for (std::size_t h = begin; h < end; ++h) {
        const MeshFace& f = faces[found[h].face];
        insert(reached, f.tet);
        insert(reached, f.other);
        if (f.other == kOutside) insert(trace.exit_tets, f.tet);
      }
      entered = reached;
    } else {
      used.assign(end - begin, 0);
      for (bool stepped = true; stepped;) {
        stepped = false;
        for (std::size_t h = begin; h < end; ++h) {
          if (used[h - begin]) continue;
          const MeshFace& f = faces[found[h].face];
          const bool at_tet = contains(reached, f.tet);
          const bool at_other = f.other != kOutside && contains(reached, f.other);
          if (!at_tet && !at_other) continue;
          used[h - begin] = 1;
          stepped = true;
          if (at_tet) {
            insert(reached, f.other);
            if (f.other == kOutside) insert(trace.exit_tets, f.tet);
          }
          if (at_other) insert(reached, f.tet);
        }
      }
      entered.assign(reached.begin() + long(from), reached.end());
      if (entered.empty()) entered = reached;
    }
    possible = reached;
    begin = end;
  }
  for (std::uint32_t x : entered) {
    if (x == kOutside)
      trace.outside = true;
    else
      trace.end_tets.push_back(x);
  }
  return trace;
}

}  // namespace tetrapage
