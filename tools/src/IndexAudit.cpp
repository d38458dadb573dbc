#include "tetrapage/tools/IndexAudit.h"
#include "tetrapage/formats/index/IndexSchema.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <unordered_map>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/Manifest.h"
#include "tetrapage/runtime/geometry/Box.h"
#include "tetrapage/runtime/paging/Shard.h"
#include "tetrapage/tools/Random.h"

namespace tetrapage {

namespace schema = index_schema;
namespace {

using Epeck = CGAL::Exact_predicates_exact_constructions_kernel;

Epeck::Point_3 to_epeck(const Vec3& p) { return {p[0], p[1], p[2]}; }

// A set of ids as (count, sum and xor of a mix of each id): equal sets give equal digests, and
// unequal ones collide with probability about 2^-64.
struct IdDigest {
  std::atomic<std::uint64_t> count{0}, sum{0}, mixed{0};
  static std::uint64_t mix(std::uint64_t id) {
    id += 0x9e3779b97f4a7c15ull;
    id = (id ^ (id >> 30)) * 0xbf58476d1ce4e5b9ull;
    id = (id ^ (id >> 27)) * 0x94d049bb133111ebull;
    return id ^ (id >> 31);
  }
  void add(std::uint64_t id) { add_mixed(mix(id)); }
  void add_mixed(std::uint64_t m) {
    count.fetch_add(1, std::memory_order_relaxed);
    sum.fetch_add(m, std::memory_order_relaxed);
    mixed.fetch_xor(m * 0xff51afd7ed558ccdull + 1, std::memory_order_relaxed);
  }
  bool same(const IdDigest& other) const {
    return count == other.count && sum == other.sum && mixed == other.mixed;
  }
};

// A triangle as one digest element: its id and its corners' bits, 0 and -0 alike (the shard
// format stores both as 0).
std::uint64_t triangle_key(std::uint64_t id, const std::array<Vec3, 3>& corners) {
  std::uint64_t key = IdDigest::mix(id);
  for (const Vec3& corner : corners)
    for (const double x : corner) key = IdDigest::mix(key ^ std::bit_cast<std::uint64_t>(x + 0.0));
  return key;
}

// What one tet should hold and what it holds: ids alone, and ids with coordinates.
struct TetDigests {
  IdDigest ids, triangles;
};

// The chosen tets by the uniform-grid cells their boxes overlap; a tet over many cells (the
// big tets of the enlarged bounding box) is in `everywhere` instead.
class TetGrid {
 public:
  TetGrid(const TetMesh& mesh, std::span<const std::uint32_t> tets) {
    for (const std::uint32_t t : tets) bounds_.extend(mesh.bounds(t));
    const auto side = std::uint32_t(std::clamp(std::cbrt(double(tets.size())), 1.0, 128.0));
    cells_ = {side, side, side};
    for (int k = 0; k < 3; ++k) size_[k] = std::max(bounds_.hi[k] - bounds_.lo[k], 1e-300) / side;
    lists_.resize(std::size_t(side) * side * side);
    for (std::uint32_t i = 0; i < tets.size(); ++i) {
      const auto [lo, hi] = range(mesh.bounds(tets[i]));
      const std::uint64_t count =
          std::uint64_t(hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1);
      if (count > 64) {
        everywhere_.push_back(i);
        continue;
      }
      for (std::uint32_t z = lo[2]; z <= hi[2]; ++z)
        for (std::uint32_t y = lo[1]; y <= hi[1]; ++y)
          for (std::uint32_t x = lo[0]; x <= hi[0]; ++x) lists_[index(x, y, z)].push_back(i);
    }
  }

  // Calls visit(i) for each chosen tet (its position in `tets`) that may overlap `box`; a tet
  // may come more than once.
  template <class Visit>
  void for_each_near(const BoundingBox& box, Visit&& visit) const {
    for (const std::uint32_t i : everywhere_) visit(i);
    if (!geometry::boxes_overlap(box, bounds_)) return;
    const auto [lo, hi] = range(box);
    for (std::uint32_t z = lo[2]; z <= hi[2]; ++z)
      for (std::uint32_t y = lo[1]; y <= hi[1]; ++y)
        for (std::uint32_t x = lo[0]; x <= hi[0]; ++x)
          for (const std::uint32_t i : lists_[index(x, y, z)]) visit(i);
  }

 private:
  std::pair<std::array<std::uint32_t, 3>, std::array<std::uint32_t, 3>> range(const BoundingBox& box) const {
    std::array<std::uint32_t, 3> lo{}, hi{};
    for (int k = 0; k < 3; ++k) {
      auto cell = [&](double v) {
        const double c = std::floor((v - bounds_.lo[k]) / size_[k]);
        return std::uint32_t(std::clamp(c, 0.0, double(cells_[k] - 1)));
      };
      lo[k] = cell(box.lo[k]);
      hi[k] = cell(box.hi[k]);
    }
    return {lo, hi};
  }
  std::size_t index(std::uint32_t x, std::uint32_t y, std::uint32_t z) const {
    return (std::size_t(z) * cells_[1] + y) * cells_[0] + x;
  }

  BoundingBox bounds_;
  std::array<std::uint32_t, 3> cells_{};
  std::array<double, 3> size_{};
  std::vector<std::vector<std::uint32_t>> lists_;
  std::vector<std::uint32_t> everywhere_;
};

}  // namespace

std::vector<std::filesystem::path> source_inputs(const IndexHeader& header, const std::filesystem::path& index) {
  std::vector<std::filesystem::path> inputs;
  std::istringstream source(header.source);
  const std::filesystem::path folder = index.parent_path();
  for (std::string line; std::getline(source, line);) {
    if (line.empty()) continue;
    const std::size_t tab = line.find('\t');
    const std::filesystem::path from_index = line.substr(0, tab);
    std::error_code error;
    if (tab == std::string::npos) {
      inputs.push_back(from_index);
    } else if (std::filesystem::exists(folder / from_index, error)) {
      inputs.push_back(folder / from_index);
    } else {
      inputs.emplace_back(line.substr(tab + 1));  // the absolute path, found or not
    }
  }
  if (inputs.empty())
    throw FormatError(index.string() + ": its 'source' attribute names no input: give the model's files after the index");
  return inputs;
}


void AuditFindings::add(std::string problem) {
  ++mismatches;
  if (problems.size() < 100) problems.push_back(std::move(problem));
}

namespace {

// The model's triangles meeting each chosen tet, streamed one piece at a time with ids counted
// as preprocess counts them (input order); returns the model's triangle count.
std::uint64_t expected_digests(const TetMesh& mesh, std::span<const std::uint32_t> tets,
                               CoordinateCheck coordinates, std::span<const InputPiece> model,
                               std::vector<TetDigests>& expected, Progress& progress) {
  std::vector<Epeck::Tetrahedron_3> solids;
  std::vector<BoundingBox> boxes;
  solids.reserve(tets.size());
  for (const std::uint32_t t : tets) {
    const auto c = mesh.corners(t);
    solids.emplace_back(to_epeck(c[0]), to_epeck(c[1]), to_epeck(c[2]), to_epeck(c[3]));
    boxes.push_back(mesh.bounds(t));
  }
  const TetGrid grid(mesh, tets);
  std::uint64_t first_id = 0;
  for (const InputPiece& piece : model) {
    const TriangleSoup soup = load_input_piece(piece);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, soup.triangle_count(), 1024),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        std::vector<std::uint32_t> near;
                        for (std::size_t t = range.begin(); t < range.end(); ++t) {
                          const auto c = soup.corners(t);
                          BoundingBox box;
                          for (const auto& p : c) box.extend(p);
                          near.clear();
                          grid.for_each_near(box, [&](std::uint32_t i) { near.push_back(i); });
                          std::sort(near.begin(), near.end());
                          near.erase(std::unique(near.begin(), near.end()), near.end());
                          if (near.empty()) continue;
                          const Epeck::Triangle_3 triangle(to_epeck(c[0]), to_epeck(c[1]), to_epeck(c[2]));
                          for (const std::uint32_t i : near) {
                            if (!geometry::boxes_overlap(box, boxes[i]) ||
                                !CGAL::do_intersect(triangle, solids[i]))
                              continue;
                            expected[i].ids.add(first_id + t);
                            if (coordinates == CoordinateCheck::exact)
                              expected[i].triangles.add_mixed(triangle_key(first_id + t, c));
                          }
                        }
                      });
    first_id += soup.triangle_count();
    progress.advance();
  }
  return first_id;
}

// "x is 0.5 (0x3fe0000000000000)": a coordinate with its bits, so that a one-bit change shows.
std::string coordinate_text(int axis, double value) {
  char text[96];
  std::snprintf(text, sizeof text, "%c is %.17g (0x%016llx)", "xyz"[axis], value,
                (unsigned long long)std::bit_cast<std::uint64_t>(value));
  return text;
}

// Names every stored coordinate of `differing` that is not the model's: streams the model
// again for the ids those tets hold (only when a digest already found a difference).
void name_coordinate_differences(std::span<const std::pair<std::uint32_t, TetContents>> differing,
                                 std::span<const InputPiece> model, AuditFindings& findings) {
  std::unordered_multimap<std::uint64_t, std::pair<std::size_t, std::size_t>>
      wanted;  // id -> (tet, local)
  for (std::size_t k = 0; k < differing.size(); ++k)
    for (std::size_t local = 0; local < differing[k].second.triangles.size(); ++local)
      wanted.emplace(differing[k].second.triangles[local].id, std::pair{k, local});
  std::uint64_t first_id = 0;
  for (const InputPiece& piece : model) {
    const TriangleSoup soup = load_input_piece(piece);
    for (std::size_t t = 0; t < soup.triangle_count(); ++t) {
      const auto [begin, end] = wanted.equal_range(first_id + t);
      for (auto at = begin; at != end; ++at) {
        const auto& [tet, contents] = differing[at->second.first];
        const StoredTriangle& stored = contents.triangles[at->second.second];
        const auto model_corners = soup.corners(t);
        for (int corner = 0; corner < 3; ++corner)
          for (int axis = 0; axis < 3; ++axis) {
            const double kept = stored.corners[corner][axis], read = model_corners[corner][axis];
            if (kept == read) continue;
            findings.add(contents.shard + " (tet " + std::to_string(tet) + ") triangle " +
                         std::to_string(stored.id) + " (local " +
                         std::to_string(at->second.second) + ") corner " + std::to_string(corner) +
                         ": stored " + coordinate_text(axis, kept) + ", the model's " +
                         coordinate_text(axis, read));
          }
      }
    }
    first_id += soup.triangle_count();
  }
}

}  // namespace

void audit_binning(const TetMesh& mesh, std::span<const std::uint32_t> tets,
                   const StoredTriangles& stored, CoordinateCheck coordinates,
                   std::uint64_t input_triangles, std::span<const InputPiece> model,
                   AuditFindings& findings, Progress& progress) {
  for (const std::uint32_t t : tets)
    if (t >= mesh.tet_count())
      throw InputError("tet " + std::to_string(t) + " is beyond the index's " +
                       std::to_string(mesh.tet_count()) + " tets");
  std::vector<TetDigests> expected(tets.size());
  const std::uint64_t model_triangles =
      expected_digests(mesh, tets, coordinates, model, expected, progress);
  findings.triangles_read += model_triangles;
  if (model_triangles != input_triangles)
    findings.add("the inputs hold " + std::to_string(model_triangles) +
                 " triangles, the index was built from " + std::to_string(input_triangles) +
                 ": they are not its model");

  // Tets whose ids agree but whose coordinates do not; a few are named triangle by triangle.
  constexpr std::size_t kNamedTets = 16;
  std::vector<std::pair<std::uint32_t, TetContents>> differing;
  for (std::size_t i = 0; i < tets.size(); ++i) {
    TetContents contents = stored(tets[i]);
    TetDigests held;
    for (const StoredTriangle& triangle : contents.triangles) {
      held.ids.add(triangle.id);
      if (coordinates == CoordinateCheck::exact)
        held.triangles.add_mixed(triangle_key(triangle.id, triangle.corners));
    }
    ++findings.tets_checked;
    if (!held.ids.same(expected[i].ids)) {
      findings.add("tet " + std::to_string(tets[i]) + " holds " +
                   std::to_string(held.ids.count.load()) +
                   " triangles; the model's triangles that meet it are " +
                   std::to_string(expected[i].ids.count.load()) +
                   (held.ids.count == expected[i].ids.count ? " (other ones)" : ""));
    } else if (!held.triangles.same(expected[i].triangles)) {
      if (differing.size() < kNamedTets)
        differing.emplace_back(tets[i], std::move(contents));
      else
        findings.add(contents.shard + " (tet " + std::to_string(tets[i]) +
                     ") stores coordinates that are not the model's");
    }
  }
  if (!differing.empty()) name_coordinate_differences(differing, model, findings);
}

void audit_binning(const TetMesh& mesh, std::span<const std::uint32_t> tets,
                   const StoredIds& stored_ids, std::uint64_t input_triangles,
                   std::span<const InputPiece> model, AuditFindings& findings, Progress& progress) {
  const StoredTriangles stored = [&](std::uint32_t tet) {
    TetContents contents{"tet " + std::to_string(tet) + "'s shard", {}};
    for (const std::uint64_t id : stored_ids(tet)) contents.triangles.push_back({id, {}});
    return contents;
  };
  audit_binning(mesh, tets, stored, CoordinateCheck::ids_only, input_triangles, model, findings,
                progress);
}

void audit_binning(const IndexReader& index, std::span<const InputPiece> model,
                   std::span<const std::uint32_t> tets, AuditFindings& findings, Progress& progress) {
  const TetMesh mesh = index.read_mesh();
  const auto tet_shard = index.read_table_uint32(schema::table::tet_shard);
  const StoredTriangles stored = [&](std::uint32_t tet) {
    const std::uint32_t shard = tet < tet_shard.size() ? tet_shard[tet] : TetMesh::no_neighbour;
    TetContents contents{"shard " + std::to_string(shard), {}};
    if (shard == TetMesh::no_neighbour) return contents;
    const Shard decoded = Shard::decode(index.read_shard(shard), contents.shard);
    for (std::uint32_t local = 0; local < decoded.triangle_count(); ++local)
      contents.triangles.push_back({decoded.triangle_id(local), decoded.triangle(local)});
    return contents;
  };
  const CoordinateCheck coordinates =
      index.header().precision == "float" ? CoordinateCheck::ids_only : CoordinateCheck::exact;
  audit_binning(mesh, tets, stored, coordinates, index.header().input_triangles, model, findings,
                progress);
}

void audit_shard_queries(const Shard& shard, const std::string& label, std::uint32_t boxes,
                         std::uint64_t seed, AuditFindings& findings) {
  const std::uint32_t n = shard.triangle_count();
  std::vector<geometry::Triangle> triangles(n);
  std::vector<BoundingBox> triangle_boxes(n);
  for (std::uint32_t local = 0; local < n; ++local) {
    triangles[local] = shard.triangle(local);
    for (const auto& p : triangles[local]) triangle_boxes[local].extend(p);
  }
  Random random(seed);
  const geometry::Box& bounds = shard.bounds();
  std::vector<std::uint32_t> got, expected;
  for (std::uint32_t b = 0; b < boxes; ++b) {
    geometry::Box box;
    for (int k = 0; k < 3; ++k) {
      const double extent = bounds.hi[k] - bounds.lo[k];
      const double half = 0.5 * extent * std::pow(10.0, random.uniform(-2.0, std::log10(0.5)));
      const double centre = random.uniform(bounds.lo[k], bounds.hi[k]);
      box.lo[k] = centre - half;
      box.hi[k] = centre + half;
    }
    got.clear();
    shard.for_each_candidate(box, [&](std::uint32_t local) { got.push_back(local); });
    std::sort(got.begin(), got.end());
    expected.clear();
    const Epeck::Iso_cuboid_3 cuboid(to_epeck(box.lo), to_epeck(box.hi));
    for (std::uint32_t local = 0; local < n; ++local) {
      if (!geometry::boxes_overlap(box, triangle_boxes[local])) continue;
      const auto& t = triangles[local];
      if (CGAL::do_intersect(Epeck::Triangle_3(to_epeck(t[0]), to_epeck(t[1]), to_epeck(t[2])), cuboid))
        expected.push_back(local);
    }
    ++findings.boxes_checked;
    if (got == expected) continue;
    std::uint32_t missing = 0, extra = 0;
    for (const std::uint32_t local : expected) missing += !std::binary_search(got.begin(), got.end(), local);
    for (const std::uint32_t local : got) extra += !std::binary_search(expected.begin(), expected.end(), local);
    char text[256];
    std::snprintf(text, sizeof text,
                  ": the query of box [%.17g %.17g %.17g]-[%.17g %.17g %.17g] misses %u and adds %u of the %zu "
                  "stored triangles that meet it",
                  box.lo[0], box.lo[1], box.lo[2], box.hi[0], box.hi[1], box.hi[2], missing, extra, expected.size());
    findings.add(label + text);
  }
  ++findings.shards_checked;
}

void audit_shard_queries(const IndexReader& index, std::span<const std::uint32_t> shards,
                         std::uint32_t boxes, std::uint64_t seed, AuditFindings& findings,
                         Progress& progress) {
  for (const std::uint32_t s : shards) {
    if (s >= index.shard_count())
      throw InputError("shard " + std::to_string(s) + " is beyond the index's " +
                       std::to_string(index.shard_count()) + " shards");
    const std::string label = "shard " + std::to_string(s);
    audit_shard_queries(Shard::decode(index.read_shard(s), label), label, boxes,
                        seed * 0x9e3779b97f4a7c15ull + s, findings);
    progress.advance();
  }
}

}  // namespace tetrapage
