#include "tetrapage/runtime/Shard.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>
#include <string>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

#include "tetrapage/formats/Error.h"
#include "tetrapage/runtime/ShardArena.h"

namespace tetrapage {

static_assert(std::endian::native == std::endian::little,
              "shard payloads are little-endian and decoded by copying");

namespace {

/// The marks of the current thread's outermost grid query: an epoch stamp per triangle, so
/// a query resets nothing but one counter.
struct ThreadMarks {
  std::vector<std::uint32_t> stamps;
  std::uint32_t epoch = 0;
  bool busy = false;
};

ThreadMarks& thread_marks() {
  thread_local ThreadMarks marks;
  return marks;
}

/// Reads the payload, checking every access against its size.
class Reader {
 public:
  Reader(std::span<const std::byte> payload, std::string_view context)
      : payload_(payload), context_(context) {}

  [[noreturn]] void fail(const std::string& what) const {
    throw FormatError(std::string(context_) + ": " + what);
  }
  template <class Value>
  [[noreturn]] void fail(const std::string& field, const Value& value,
                         const std::string& rule) const {
    std::ostringstream out;
    out.precision(17);
    out << field << " = " << value << " (" << rule << ")";
    fail(out.str());
  }

  template <class T>
  T at(std::size_t offset) const {
    if (offset > payload_.size() || payload_.size() - offset < sizeof(T))
      fail("payload of " + std::to_string(payload_.size()) + " bytes is too short to read " +
           std::to_string(sizeof(T)) + " bytes at offset " + std::to_string(offset));
    T value;
    std::memcpy(&value, payload_.data() + offset, sizeof(T));
    return value;
  }

  /// Copies `count` values of `T` from a section, which must hold them, into `values` (in
  /// its own memory resource).
  template <class T>
  void array(std::pmr::vector<T>& values, std::size_t offset, std::size_t end, std::uint64_t count,
             const char* section) const {
    const std::uint64_t available = end - offset;  // end >= offset is checked by the caller
    if (count > available / sizeof(T))
      fail(std::string("section ") + section + " holds " + std::to_string(available) +
           " bytes, fewer than " + std::to_string(count) + " values of " +
           std::to_string(sizeof(T)) + " bytes");
    values.resize(count);
    if (count > 0) std::memcpy(values.data(), payload_.data() + offset, count * sizeof(T));
  }

  std::size_t size() const { return payload_.size(); }

 private:
  std::span<const std::byte> payload_;
  std::string_view context_;
};

bool finite(const geometry::Point& p) {
  return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

bool box_contains_box(const geometry::Box& outer, const geometry::Box& inner) {
  for (int k = 0; k < 3; ++k)
    if (!(outer.lo[k] <= inner.lo[k] && inner.hi[k] <= outer.hi[k])) return false;
  return true;
}

const char* section_name(std::size_t s) {
  static constexpr const char* names[] = {"vertices",     "triangles", "ids",       "part_palette",
                                          "part_indices", "structure", "references"};
  return s < shard_format::section_count ? names[s] : "end";
}

}  // namespace

Shard::Marks::Marks(std::uint32_t triangle_count) {
  ThreadMarks& marks = thread_marks();
  if (marks.busy) {  // a query inside another's visit: its own marks, not the thread's
    own_.assign(triangle_count, 0);
    stamps_ = own_.data();
    epoch_ = 1;
    return;
  }
  marks.busy = true;
  borrowed_ = true;
  if (++marks.epoch == 0) {
    std::fill(marks.stamps.begin(), marks.stamps.end(), 0u);
    marks.epoch = 1;
  }
  if (marks.stamps.size() < triangle_count) marks.stamps.resize(triangle_count, 0u);
  stamps_ = marks.stamps.data();
  epoch_ = marks.epoch;
}

Shard::Marks::~Marks() {
  if (borrowed_) thread_marks().busy = false;
}

std::uint32_t Shard::component_id(std::uint32_t local) const {
  switch (part_index_bytes_) {
    case 0:
      return part_palette_[0];
    case 1:
      return part_palette_[part_indices_[local]];
    case 2: {
      std::uint16_t i;
      std::memcpy(&i, part_indices_.data() + 2 * std::size_t(local), 2);
      return part_palette_[i];
    }
    default: {
      std::uint32_t i;
      std::memcpy(&i, part_indices_.data() + 4 * std::size_t(local), 4);
      return part_palette_[i];
    }
  }
}

Shard::Shard(std::pmr::memory_resource* memory)
    : vertices32_(memory),
      vertices64_(memory),
      indices16_(memory),
      indices32_(memory),
      id_offsets32_(memory),
      id_offsets64_(memory),
      part_palette_(memory),
      part_indices_(memory),
      cell_offsets_(memory),
      references16_(memory),
      references32_(memory),
      nodes_(memory),
      node_boxes_(memory) {}

std::size_t Shard::memory_bytes() const {
  auto bytes = [](const auto& v) {
    const std::size_t requested = v.capacity() * sizeof(v[0]);
    return dynamic_cast<const ShardArena*>(v.get_allocator().resource()) != nullptr
               ? ShardArena::block_bytes(requested)
               : requested;
  };
  return sizeof(Shard) + bytes(vertices32_) + bytes(vertices64_) + bytes(indices16_) +
         bytes(indices32_) + bytes(id_offsets32_) + bytes(id_offsets64_) + bytes(part_palette_) +
         bytes(part_indices_) + bytes(cell_offsets_) + bytes(references16_) + bytes(references32_) +
         bytes(nodes_) + bytes(node_boxes_);
}

std::uint32_t Shard::children_overlapping(std::uint32_t first, std::uint32_t count,
                                          const float lo[3], const float hi[3]) const {
  const float* b = node_boxes_.data() + first;
  const std::size_t n = node_stride_;
  std::uint32_t mask = 0;
#if defined(__SSE2__)
  const __m128 lx = _mm_set1_ps(lo[0]), ly = _mm_set1_ps(lo[1]), lz = _mm_set1_ps(lo[2]);
  const __m128 hx = _mm_set1_ps(hi[0]), hy = _mm_set1_ps(hi[1]), hz = _mm_set1_ps(hi[2]);
  for (std::uint32_t c = 0; c < count; c += 4, b += 4) {
    __m128 m =
        _mm_and_ps(_mm_cmple_ps(_mm_loadu_ps(b), hx), _mm_cmpge_ps(_mm_loadu_ps(b + 3 * n), lx));
    m = _mm_and_ps(m, _mm_and_ps(_mm_cmple_ps(_mm_loadu_ps(b + n), hy),
                                 _mm_cmpge_ps(_mm_loadu_ps(b + 4 * n), ly)));
    m = _mm_and_ps(m, _mm_and_ps(_mm_cmple_ps(_mm_loadu_ps(b + 2 * n), hz),
                                 _mm_cmpge_ps(_mm_loadu_ps(b + 5 * n), lz)));
    mask |= std::uint32_t(_mm_movemask_ps(m)) << c;
  }
#else
  for (std::uint32_t c = 0; c < count; ++c)
    if (b[c] <= hi[0] && b[3 * n + c] >= lo[0] && b[n + c] <= hi[1] && b[4 * n + c] >= lo[1] &&
        b[2 * n + c] <= hi[2] && b[5 * n + c] >= lo[2])
      mask |= 1u << c;
#endif
  return mask & ((1u << count) - 1);
}

bool shard_format::grid_cell_range(double lo, double cell_size, std::uint32_t cells, double low,
                                   double high, std::uint32_t& first, std::uint32_t& last) {
  auto boundary = [&](std::uint32_t i) { return grid_boundary(lo, cell_size, i); };
  if (!(low <= high) || high < boundary(0) || low > boundary(cells)) return false;
  // An estimate, then exact steps against the boundaries (a step or two at most, unless the
  // estimate was clamped from far outside).
  auto estimate = [&](double x) {
    const double i = std::floor((x - lo) / cell_size);
    return std::uint32_t(std::clamp(std::isnan(i) ? 0.0 : i, 0.0, double(cells - 1)));
  };
  // first: the lowest cell i whose upper boundary b(i + 1) >= low.
  std::uint32_t i = estimate(low);
  while (i > 0 && boundary(i) >= low) --i;
  while (i + 1 < cells && boundary(i + 1) < low) ++i;
  // last: the highest cell j whose lower boundary b(j) <= high.
  std::uint32_t j = estimate(high);
  while (j + 1 < cells && boundary(j + 1) <= high) ++j;
  while (j > 0 && boundary(j) > high) --j;
  if (j < i) return false;
  first = i;
  last = j;
  return true;
}

Shard Shard::decode(std::span<const std::byte> payload, std::string_view context,
                    DecodeChecks checks, std::pmr::memory_resource* memory) {
  namespace sf = shard_format;
  const Reader in(payload, context);
  if (payload.size() < sf::kHeaderBytes)
    in.fail("payload size", payload.size(),
            "shorter than the " + std::to_string(sf::kHeaderBytes) + "-byte header");
  if (!std::equal(sf::kMagic.begin(), sf::kMagic.end(), payload.begin()))
    in.fail("magic", in.at<std::uint32_t>(0), "not a shard payload: expected 'TPSH'");
  const auto version = in.at<std::uint16_t>(4);
  if (version != sf::kVersion)
    in.fail("version", version, "this reader knows version " + std::to_string(sf::kVersion));

  const bool check_boxes = checks == DecodeChecks::full;
  Shard shard(memory != nullptr ? memory : std::pmr::get_default_resource());
  const auto kind = in.at<std::uint8_t>(6);
  if (kind > 1) in.fail("kind", unsigned(kind), "0 grid or 1 rtree");
  shard.kind_ = ShardKind(kind);
  const auto precision = in.at<std::uint8_t>(7);
  if (precision > 1) in.fail("precision", unsigned(precision), "0 float32 or 1 float64");
  shard.precision_ = StoredPrecision(precision);
  const auto vertex_index_bytes = in.at<std::uint8_t>(8);
  const auto id_bytes = in.at<std::uint8_t>(9);
  const auto part_index_bytes = in.at<std::uint8_t>(10);
  const auto reference_bytes = in.at<std::uint8_t>(11);
  const auto vertex_count = in.at<std::uint32_t>(12);
  const auto triangle_count = in.at<std::uint32_t>(16);
  const auto part_count = in.at<std::uint32_t>(20);
  const auto structure_count = in.at<std::uint32_t>(24);
  const auto reference_count = in.at<std::uint32_t>(28);
  shard.id_base_ = in.at<std::uint64_t>(32);
  for (int k = 0; k < 3; ++k) {
    shard.origin_[k] = in.at<double>(40 + 8 * k);
    shard.grid_cells_[k] = in.at<std::uint32_t>(64 + 4 * k);
    shard.grid_lo_[k] = in.at<double>(80 + 8 * k);
    shard.grid_cell_size_[k] = in.at<double>(104 + 8 * k);
  }
  if (!finite(shard.origin_)) in.fail("origin is not finite");
  if (triangle_count == 0) in.fail("triangle_count", 0, "a shard holds at least one triangle");
  if (vertex_count == 0) in.fail("vertex_count", 0, "a shard holds at least one vertex");
  if (vertex_index_bytes != (vertex_count <= 65536 ? 2 : 4))
    in.fail("vertex_index_bytes", unsigned(vertex_index_bytes),
            "2 when vertex_count <= 65536, else 4; vertex_count = " + std::to_string(vertex_count));
  if (id_bytes != 4 && id_bytes != 8) in.fail("id_bytes", unsigned(id_bytes), "4 or 8");
  if (part_count == 0) in.fail("part_count", 0, "at least one part");
  const unsigned expected_part_bytes =
      part_count == 1 ? 0 : (part_count <= 256 ? 1 : (part_count <= 65536 ? 2 : 4));
  if (part_index_bytes != expected_part_bytes)
    in.fail("part_index_bytes", unsigned(part_index_bytes),
            "expected " + std::to_string(expected_part_bytes) + " for part_count " +
                std::to_string(part_count));
  shard.part_index_bytes_ = part_index_bytes;
  shard.triangle_count_ = triangle_count;
  shard.vertex_count_ = vertex_count;

  std::array<std::uint64_t, sf::section_count + 1> offset{};
  for (std::size_t s = 0; s <= sf::section_count; ++s) {
    offset[s] = in.at<std::uint64_t>(128 + 8 * s);
    const std::uint64_t previous = s == 0 ? sf::kHeaderBytes : offset[s - 1];
    if (offset[s] < previous || offset[s] > payload.size())
      in.fail(
          std::string("offset of section ") + section_name(s), offset[s],
          "must lie in [" + std::to_string(previous) + ", " + std::to_string(payload.size()) + "]");
  }
  if (offset[sf::section_count] != payload.size())
    in.fail("end offset", offset[sf::section_count],
            "must equal the payload size " + std::to_string(payload.size()));
  auto begin_of = [&](sf::Section s) { return std::size_t(offset[s]); };
  auto end_of = [&](sf::Section s) { return std::size_t(offset[s + 1]); };

  // Vertices.
  const std::uint64_t coordinates = 3 * std::uint64_t(vertex_count);
  if (shard.precision_ == StoredPrecision::float32)
    in.array(shard.vertices32_, begin_of(sf::vertices), end_of(sf::vertices), coordinates,
             "vertices");
  else
    in.array(shard.vertices64_, begin_of(sf::vertices), end_of(sf::vertices), coordinates,
             "vertices");
  // The stored vertices, kept for the R-tree's leaf checks below (cheaper than each
  // triangle's box there: a vertex is shared by about six triangles).
  std::vector<geometry::Point> stored;
  if (check_boxes && shard.kind_ == ShardKind::rtree) {
    stored.resize(vertex_count);
    for (std::uint32_t v = 0; v < vertex_count; ++v)
      stored[v] = shard.precision_ == StoredPrecision::float32 ? shard.stored_vertex<float>(v)
                                                               : shard.stored_vertex<double>(v);
  }
  // The bounds from the extreme stored values per axis (o + double(r) rounds monotonically in
  // r), in loops the compiler vectorises; the stored vertices are finite when their bounds are.
  auto extremes = [&](const auto& relative) {
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    bool nan = false;
    for (std::uint32_t v = 0; v < vertex_count; ++v)
      for (int k = 0; k < 3; ++k) {
        const double r = double(relative[3 * std::size_t(v) + std::size_t(k)]);
        nan |= r != r;
        lo[k] = std::min(lo[k], r);
        hi[k] = std::max(hi[k], r);
      }
    for (int k = 0; k < 3; ++k) {
      shard.bounds_.lo[k] = shard.origin_[k] + lo[k];
      shard.bounds_.hi[k] = shard.origin_[k] + hi[k];
    }
    return !nan && finite(shard.bounds_.lo) && finite(shard.bounds_.hi);
  };
  const bool all_finite = shard.precision_ == StoredPrecision::float32
                              ? extremes(shard.vertices32_)
                              : extremes(shard.vertices64_);
  if (!all_finite) {
    for (std::uint32_t v = 0; v < vertex_count; ++v) {
      const geometry::Point p = shard.precision_ == StoredPrecision::float32
                                    ? shard.stored_vertex<float>(v)
                                    : shard.stored_vertex<double>(v);
      if (!finite(p)) in.fail("stored vertex", v, "its coordinates are not finite");
    }
    in.fail("stored vertices' bounds are not finite");
  }

  // Triangles.
  const std::uint64_t corners = 3 * std::uint64_t(triangle_count);
  if (vertex_index_bytes == 2)
    in.array(shard.indices16_, begin_of(sf::triangles), end_of(sf::triangles), corners,
             "triangles");
  else
    in.array(shard.indices32_, begin_of(sf::triangles), end_of(sf::triangles), corners,
             "triangles");
  for (std::uint32_t t = 0; t < triangle_count; ++t)
    for (int k = 0; k < 3; ++k)
      if (shard.corner(t, k) >= vertex_count)
        in.fail("corner " + std::to_string(k) + " of triangle " + std::to_string(t),
                shard.corner(t, k), "vertex_count is " + std::to_string(vertex_count));

  // Ids and parts.
  if (id_bytes == 4)
    in.array(shard.id_offsets32_, begin_of(sf::ids), end_of(sf::ids), triangle_count, "ids");
  else
    in.array(shard.id_offsets64_, begin_of(sf::ids), end_of(sf::ids), triangle_count, "ids");
  in.array(shard.part_palette_, begin_of(sf::part_palette), end_of(sf::part_palette), part_count,
           "part_palette");
  in.array(shard.part_indices_, begin_of(sf::part_indices), end_of(sf::part_indices),
           std::uint64_t(triangle_count) * part_index_bytes, "part_indices");
  // One loop per index width: a copy of a variable width per triangle was an eighth of decode.
  auto check_part_indices = [&]<class Index>() {
    for (std::uint32_t t = 0; t < triangle_count; ++t) {
      Index i = 0;
      std::memcpy(&i, shard.part_indices_.data() + std::size_t(t) * sizeof(Index), sizeof(Index));
      if (i >= part_count)
        in.fail("part index of triangle " + std::to_string(t), std::uint32_t(i),
                "part_count is " + std::to_string(part_count));
    }
  };
  if (part_index_bytes == 1) check_part_indices.template operator()<std::uint8_t>();
  if (part_index_bytes == 2) check_part_indices.template operator()<std::uint16_t>();
  if (part_index_bytes == 4) check_part_indices.template operator()<std::uint32_t>();

  if (shard.kind_ == ShardKind::grid) {
    std::uint64_t cells = 1;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t n = shard.grid_cells_[k];
      if (n == 0) in.fail("grid cells along axis " + std::to_string(k), 0, "at least 1");
      cells *= n;  // < 2^96 cannot overflow before the check below stops it
      if (cells > structure_count)
        in.fail("grid cell count", cells,
                "the product of cells per axis must equal structure_count " +
                    std::to_string(structure_count));
      if (!(std::isfinite(shard.grid_lo_[k]) && std::isfinite(shard.grid_cell_size_[k]) &&
            shard.grid_cell_size_[k] > 0 && std::isfinite(shard.grid_boundary(k, n))))
        in.fail(
            "grid lo / cell size along axis " + std::to_string(k),
            std::to_string(shard.grid_lo_[k]) + " / " + std::to_string(shard.grid_cell_size_[k]),
            "finite, with a positive cell size");
      if (!(shard.grid_boundary(k, 0) <= shard.bounds_.lo[k] &&
            shard.bounds_.hi[k] <= shard.grid_boundary(k, n)))
        in.fail("grid extent along axis " + std::to_string(k),
                std::to_string(shard.grid_boundary(k, 0)) + ".." +
                    std::to_string(shard.grid_boundary(k, n)),
                "must hold every stored vertex");
    }
    if (cells != structure_count)
      in.fail("grid cell count", cells,
              "must equal structure_count " + std::to_string(structure_count));
    if (reference_bytes != (triangle_count <= 65536 ? 2 : 4))
      in.fail("reference_bytes", unsigned(reference_bytes),
              "2 when triangle_count <= 65536, else 4");
    in.array(shard.cell_offsets_, begin_of(sf::structure), end_of(sf::structure), cells + 1,
             "structure");
    if (shard.cell_offsets_[0] != 0) in.fail("offset of cell 0", shard.cell_offsets_[0], "0");
    for (std::uint64_t c = 0; c < cells; ++c)
      if (shard.cell_offsets_[c + 1] < shard.cell_offsets_[c])
        in.fail(
            "offset of cell " + std::to_string(c + 1), shard.cell_offsets_[c + 1],
            "offsets must not decrease; the previous is " + std::to_string(shard.cell_offsets_[c]));
    if (shard.cell_offsets_[cells] != reference_count)
      in.fail("last cell offset", shard.cell_offsets_[cells],
              "must equal reference_count " + std::to_string(reference_count));
    if (reference_bytes == 2)
      in.array(shard.references16_, begin_of(sf::references), end_of(sf::references),
               reference_count, "references");
    else
      in.array(shard.references32_, begin_of(sf::references), end_of(sf::references),
               reference_count, "references");
    for (std::uint32_t r = 0; r < reference_count; ++r) {
      const std::uint32_t t =
          reference_bytes == 2 ? shard.references16_[r] : shard.references32_[r];
      if (t >= triangle_count)
        in.fail("reference " + std::to_string(r), t,
                "triangle_count is " + std::to_string(triangle_count));
    }
  } else {
    if (reference_count != 0 || reference_bytes != 0)
      in.fail("reference_count / reference_bytes of an R-tree",
              std::to_string(reference_count) + " / " + std::to_string(reference_bytes), "0");
    if (structure_count == 0) in.fail("R-tree node count", 0, "at least the root");
    const std::size_t record = sf::node_record_bytes(shard.precision_);
    const std::size_t begin = begin_of(sf::structure);
    if (std::uint64_t(structure_count) > (end_of(sf::structure) - begin) / record)
      in.fail("R-tree node count", structure_count,
              "the structure section holds " + std::to_string(end_of(sf::structure) - begin) +
                  " bytes of " + std::to_string(record) + "-byte nodes");
    shard.nodes_.resize(structure_count);
    shard.node_stride_ = std::size_t(structure_count) + kNodeBoxPadding;
    // The padding holds empty boxes (never read into a result: children past a node's count
    // are masked off).
    shard.node_boxes_.assign(6 * shard.node_stride_, 0.0f);
    // The stored coordinates by axis, converted to floats in one pass after the loop.
    thread_local std::vector<double> relative;
    relative.resize(6 * std::size_t(structure_count));
    std::vector<geometry::Box> boxes;  // in double, for the enclosure checks
    if (check_boxes) boxes.resize(structure_count);
    std::vector<std::uint32_t> depth(structure_count, 0);
    std::vector<std::uint8_t> has_parent(structure_count, 0);
    std::vector<std::uint8_t> covered(triangle_count, 0);
    std::uint64_t leaf_triangles = 0;
    for (std::uint32_t i = 0; i < structure_count; ++i) {
      Node& node = shard.nodes_[i];
      const std::size_t at = begin + std::size_t(i) * record;
      geometry::Box box;
      for (int k = 0; k < 3; ++k) {
        const double lo = shard.precision_ == StoredPrecision::float32
                              ? double(in.at<float>(at + 4 * k))
                              : in.at<double>(at + 8 * k);
        const double hi = shard.precision_ == StoredPrecision::float32
                              ? double(in.at<float>(at + 12 + 4 * k))
                              : in.at<double>(at + 24 + 8 * k);
        box.lo[k] = shard.origin_[k] + lo;
        box.hi[k] = shard.origin_[k] + hi;
        relative[k * structure_count + i] = lo;
        relative[(3 + k) * structure_count + i] = hi;
      }
      node.first = in.at<std::uint32_t>(at + record - 8);
      node.count = in.at<std::uint32_t>(at + record - 4);
      if (!finite(box.lo) || !finite(box.hi))
        in.fail("box of R-tree node", i, "its coordinates are not finite");
      if (check_boxes) boxes[i] = box;
      if (i > 0 && !has_parent[i]) in.fail("R-tree node", i, "no node lists it as a child");
      const std::uint32_t count = node.count & ~sf::kLeafFlag;
      if (node.count & sf::kLeafFlag) {
        if (count == 0 || node.first > triangle_count || count > triangle_count - node.first)
          in.fail("triangle range of R-tree leaf " + std::to_string(i),
                  std::to_string(node.first) + "+" + std::to_string(count),
                  "non-empty, within triangle_count " + std::to_string(triangle_count));
        for (std::uint32_t t = node.first; t < node.first + count; ++t) {
          if (covered[t]) in.fail("triangle " + std::to_string(t), "", "in two R-tree leaves");
          covered[t] = 1;
          if (check_boxes)
            for (int k = 0; k < 3; ++k)
              if (!geometry::box_contains(box, stored[shard.corner(t, k)]))
                in.fail("box of R-tree leaf " + std::to_string(i), "",
                        "does not enclose its triangle " + std::to_string(t));
        }
        leaf_triangles += count;
      } else {
        if (count == 0 || count > sf::kMaxFanout || node.first <= i ||
            node.first > structure_count || count > structure_count - node.first)
          in.fail("children of R-tree node " + std::to_string(i),
                  std::to_string(node.first) + "+" + std::to_string(count),
                  "1.." + std::to_string(sf::kMaxFanout) + " nodes after it, within " +
                      std::to_string(structure_count));
        if (depth[i] + 1 >= sf::kMaxDepth)
          in.fail("depth of R-tree node " + std::to_string(i), depth[i] + 1,
                  "at most " + std::to_string(sf::kMaxDepth - 1));
        for (std::uint32_t c = node.first; c < node.first + count; ++c) {
          if (has_parent[c]) in.fail("R-tree node", c, "listed as a child twice");
          has_parent[c] = 1;
          depth[c] = depth[i] + 1;
        }
      }
    }
    // Rounded outward by a float's unit in the last place (at least; values near zero by the
    // smallest normal float: a subnormal operand costs a microcode assist, which made decode
    // of a float32 R-tree a quarter slower), clamped to the finite floats.
    constexpr double kMost = std::numeric_limits<float>::max();
    constexpr float kTiny = std::numeric_limits<float>::min();
    double largest = 0;
    for (std::size_t k = 0; k < 6; ++k) {
      const double* from = relative.data() + k * structure_count;
      float* to = shard.node_boxes_.data() + k * shard.node_stride_;
      const float side = k < 3 ? -1.0f : 1.0f;
      for (std::uint32_t i = 0; i < structure_count; ++i) {
        largest = std::max(largest, std::fabs(from[i]));
        const float f = float(std::clamp(from[i], -kMost, kMost));
        to[i] =
            std::clamp(f + side * (std::fabs(f) * 0x1p-23f + kTiny), -float(kMost), float(kMost));
      }
    }
    shard.clamped_node_boxes_ = largest > kMost;
    if (leaf_triangles != triangle_count)
      in.fail("triangles in R-tree leaves", leaf_triangles,
              "must equal triangle_count " + std::to_string(triangle_count));
    // Parents enclose children: checked after every box is read.
    for (std::uint32_t i = 0; i < structure_count && check_boxes; ++i) {
      const Node& node = shard.nodes_[i];
      if (node.count & sf::kLeafFlag) continue;
      for (std::uint32_t c = node.first; c < node.first + node.count; ++c)
        if (!box_contains_box(boxes[i], boxes[c]))
          in.fail("box of R-tree node " + std::to_string(i), "",
                  "does not enclose its child " + std::to_string(c));
    }
  }
  return shard;
}

}  // namespace tetrapage
