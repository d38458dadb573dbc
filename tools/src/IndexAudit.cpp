#include "tetrapage/tools/IndexAudit.h"
#include "tetrapage/formats/IndexSchema.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "tetrapage/formats/Error.h"
#include "tetrapage/formats/Manifest.h"
#include "tetrapage/runtime/Shard.h"
#include "tetrapage/runtime/geometry/Box.h"
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
  void add(std::uint64_t id) {
    const std::uint64_t m = mix(id);
    count.fetch_add(1, std::memory_order_relaxed);
    sum.fetch_add(m, std::memory_order_relaxed);
    mixed.fetch_xor(m * 0xff51afd7ed558ccdull + 1, std::memory_order_relaxed);
  }
  bool same(const IdDigest& other) const {
    return count == other.count && sum == other.sum && mixed == other.mixed;
  }
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

void audit_binning(const TetMesh& mesh, std::span<const std::uint32_t> tets, const StoredIds& stored_ids,
                   std::uint64_t input_triangles, std::span<const InputPiece> model,
                   AuditFindings& findings, Progress& progress) {
  for (const std::uint32_t t : tets)
    if (t >= mesh.tet_count())
      throw InputError("tet " + std::to_string(t) + " is beyond the index's " +
                       std::to_string(mesh.tet_count()) + " tets");
  std::vector<IdDigest> expected(tets.size()), stored(tets.size());
  std::vector<Epeck::Tetrahedron_3> solids;
  std::vector<BoundingBox> boxes;
  solids.reserve(tets.size());
  for (const std::uint32_t t : tets) {
    const auto c = mesh.corners(t);
    solids.emplace_back(to_epeck(c[0]), to_epeck(c[1]), to_epeck(c[2]), to_epeck(c[3]));
    boxes.push_back(mesh.bounds(t));
  }
  const TetGrid grid(mesh, tets);

  // The model, one piece at a time, with ids counted as preprocess counts them (input order).
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
                          for (const std::uint32_t i : near)
                            if (geometry::boxes_overlap(box, boxes[i]) && CGAL::do_intersect(triangle, solids[i]))
                              expected[i].add(first_id + t);
                        }
                      });
    first_id += soup.triangle_count();
    progress.advance();
  }
  findings.triangles_read += first_id;
  if (first_id != input_triangles)
    findings.add("the inputs hold " + std::to_string(first_id) + " triangles, the index was built from " +
                 std::to_string(input_triangles) + ": they are not its model");

  for (std::size_t i = 0; i < tets.size(); ++i) {
    for (const std::uint64_t id : stored_ids(tets[i])) stored[i].add(id);
    ++findings.tets_checked;
    if (!stored[i].same(expected[i]))
      findings.add("tet " + std::to_string(tets[i]) + " holds " + std::to_string(stored[i].count.load()) +
                   " triangles; the model's triangles that meet it are " +
                   std::to_string(expected[i].count.load()) +
                   (stored[i].count == expected[i].count ? " (other ones)" : ""));
  }
}

void audit_binning(const IndexReader& index, std::span<const InputPiece> model,
                   std::span<const std::uint32_t> tets, AuditFindings& findings, Progress& progress) {
  const TetMesh mesh = index.read_mesh();
  const auto tet_shard = index.read_table_uint32(schema::table::tet_shard);
  const StoredIds stored = [&](std::uint32_t tet) {
    std::vector<std::uint64_t> ids;
    const std::uint32_t shard = tet < tet_shard.size() ? tet_shard[tet] : TetMesh::no_neighbour;
    if (shard == TetMesh::no_neighbour) return ids;
    const Shard decoded = Shard::decode(index.read_shard(shard), "shard " + std::to_string(shard));
    for (std::uint32_t local = 0; local < decoded.triangle_count(); ++local) ids.push_back(decoded.triangle_id(local));
    return ids;
  };
  audit_binning(mesh, tets, stored, index.header().input_triangles, model, findings, progress);
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
