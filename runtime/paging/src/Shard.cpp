#include "tetrapage/runtime/paging/Shard.h"

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

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/runtime/paging/ShardArena.h"

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

/// Shard::decode's steps, one per part of the payload (docs/SHARD-FORMAT.md), in payload order:
/// each reads its section into the shard and checks it.
class Shard::Decoder {
 public:
  Decoder(std::span<const std::byte> payload, std::string_view context, DecodeChecks checks,
          Shard& shard)
      : payload_(payload),
        in_(payload, context),
        check_boxes_(checks == DecodeChecks::full),
        shard_(shard) {}

  void read_header();
  void read_section_offsets();
  void read_vertices();
  void read_triangles();
  void read_ids_and_parts();
  void read_grid();
  void read_rtree();

 private:
  struct RtreeChecks;
  std::size_t begin_of(shard_format::Section s) const { return std::size_t(offset_[s]); }
  std::size_t end_of(shard_format::Section s) const { return std::size_t(offset_[s + 1]); }
  void check_grid_axes(std::uint64_t& cells) const;
  void read_grid_references();
  void read_rtree_node(std::uint32_t i, std::size_t at, RtreeChecks& checks);
  void round_node_boxes_outward(const std::vector<double>& relative);
  void check_parents_enclose_children(const std::vector<geometry::Box>& boxes) const;

  std::span<const std::byte> payload_;
  const Reader in_;
  const bool check_boxes_;
  Shard& shard_;
  std::uint8_t vertex_index_bytes_ = 0, id_bytes_ = 0, part_index_bytes_ = 0, reference_bytes_ = 0;
  std::uint32_t part_count_ = 0, structure_count_ = 0, reference_count_ = 0;
  std::array<std::uint64_t, shard_format::section_count + 1> offset_{};
  /// The stored vertices, kept for the R-tree's leaf checks (cheaper than each triangle's box
  /// there: a vertex is shared by about six triangles).
  std::vector<geometry::Point> stored_;
};

void Shard::Decoder::read_header() {
  namespace sf = shard_format;
  if (payload_.size() < sf::kHeaderBytes)
    in_.fail("payload size", payload_.size(),
             "shorter than the " + std::to_string(sf::kHeaderBytes) + "-byte header");
  if (!std::equal(sf::kMagic.begin(), sf::kMagic.end(), payload_.begin()))
    in_.fail("magic", in_.at<std::uint32_t>(0), "not a shard payload: expected 'TPSH'");
  const auto version = in_.at<std::uint16_t>(4);
  if (version != sf::kVersion)
    in_.fail("version", version, "this reader knows version " + std::to_string(sf::kVersion));
  const auto kind = in_.at<std::uint8_t>(6);
  if (kind > 1) in_.fail("kind", unsigned(kind), "0 grid or 1 rtree");
  shard_.kind_ = ShardKind(kind);
  const auto precision = in_.at<std::uint8_t>(7);
  if (precision > 1) in_.fail("precision", unsigned(precision), "0 float32 or 1 float64");
  shard_.precision_ = StoredPrecision(precision);
  vertex_index_bytes_ = in_.at<std::uint8_t>(8);
  id_bytes_ = in_.at<std::uint8_t>(9);
  part_index_bytes_ = in_.at<std::uint8_t>(10);
  reference_bytes_ = in_.at<std::uint8_t>(11);
  const auto vertex_count = in_.at<std::uint32_t>(12);
  const auto triangle_count = in_.at<std::uint32_t>(16);
  part_count_ = in_.at<std::uint32_t>(20);
  structure_count_ = in_.at<std::uint32_t>(24);
  reference_count_ = in_.at<std::uint32_t>(28);
  shard_.id_base_ = in_.at<std::uint64_t>(32);
  for (int k = 0; k < 3; ++k) {
    shard_.origin_[k] = in_.at<double>(40 + 8 * k);
    shard_.grid_cells_[k] = in_.at<std::uint32_t>(64 + 4 * k);
    shard_.grid_lo_[k] = in_.at<double>(80 + 8 * k);
    shard_.grid_cell_size_[k] = in_.at<double>(104 + 8 * k);
  }
  if (!finite(shard_.origin_)) in_.fail("origin is not finite");
  if (triangle_count == 0) in_.fail("triangle_count", 0, "a shard holds at least one triangle");
  if (vertex_count == 0) in_.fail("vertex_count", 0, "a shard holds at least one vertex");
  if (vertex_index_bytes_ != (vertex_count <= 65536 ? 2 : 4))
    in_.fail(
        "vertex_index_bytes", unsigned(vertex_index_bytes_),
        "2 when vertex_count <= 65536, else 4; vertex_count = " + std::to_string(vertex_count));
  if (id_bytes_ != 4 && id_bytes_ != 8) in_.fail("id_bytes", unsigned(id_bytes_), "4 or 8");
  if (part_count_ == 0) in_.fail("part_count", 0, "at least one part");
  const unsigned expected_part_bytes =
      part_count_ == 1 ? 0 : (part_count_ <= 256 ? 1 : (part_count_ <= 65536 ? 2 : 4));
  if (part_index_bytes_ != expected_part_bytes)
    in_.fail("part_index_bytes", unsigned(part_index_bytes_),
             "expected " + std::to_string(expected_part_bytes) + " for part_count " +
                 std::to_string(part_count_));
  shard_.part_index_bytes_ = part_index_bytes_;
  shard_.triangle_count_ = triangle_count;
  shard_.vertex_count_ = vertex_count;
}

void Shard::Decoder::read_section_offsets() {
  namespace sf = shard_format;
  for (std::size_t s = 0; s <= sf::section_count; ++s) {
    offset_[s] = in_.at<std::uint64_t>(128 + 8 * s);
    const std::uint64_t previous = s == 0 ? sf::kHeaderBytes : offset_[s - 1];
    if (offset_[s] < previous || offset_[s] > payload_.size())
      in_.fail(std::string("offset of section ") + section_name(s), offset_[s],
               "must lie in [" + std::to_string(previous) + ", " + std::to_string(payload_.size()) +
                   "]");
  }
  if (offset_[sf::section_count] != payload_.size())
    in_.fail("end offset", offset_[sf::section_count],
             "must equal the payload size " + std::to_string(payload_.size()));
}

void Shard::Decoder::read_vertices() {
  namespace sf = shard_format;
  const std::uint32_t vertex_count = shard_.vertex_count_;
  const std::uint64_t coordinates = 3 * std::uint64_t(vertex_count);
  const bool float32 = shard_.precision_ == StoredPrecision::float32;
  if (float32)
    in_.array(shard_.vertices32_, begin_of(sf::vertices), end_of(sf::vertices), coordinates,
              "vertices");
  else
    in_.array(shard_.vertices64_, begin_of(sf::vertices), end_of(sf::vertices), coordinates,
              "vertices");
  if (check_boxes_ && shard_.kind_ == ShardKind::rtree) {
    stored_.resize(vertex_count);
    for (std::uint32_t v = 0; v < vertex_count; ++v)
      stored_[v] = float32 ? shard_.stored_vertex<float>(v) : shard_.stored_vertex<double>(v);
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
      shard_.bounds_.lo[k] = shard_.origin_[k] + lo[k];
      shard_.bounds_.hi[k] = shard_.origin_[k] + hi[k];
    }
    return !nan && finite(shard_.bounds_.lo) && finite(shard_.bounds_.hi);
  };
  if (float32 ? extremes(shard_.vertices32_) : extremes(shard_.vertices64_)) return;
  for (std::uint32_t v = 0; v < vertex_count; ++v) {
    const geometry::Point p =
        float32 ? shard_.stored_vertex<float>(v) : shard_.stored_vertex<double>(v);
    if (!finite(p)) in_.fail("stored vertex", v, "its coordinates are not finite");
  }
  in_.fail("stored vertices' bounds are not finite");
}

void Shard::Decoder::read_triangles() {
  namespace sf = shard_format;
  const std::uint64_t corners = 3 * std::uint64_t(shard_.triangle_count_);
  if (vertex_index_bytes_ == 2)
    in_.array(shard_.indices16_, begin_of(sf::triangles), end_of(sf::triangles), corners,
              "triangles");
  else
    in_.array(shard_.indices32_, begin_of(sf::triangles), end_of(sf::triangles), corners,
              "triangles");
  for (std::uint32_t t = 0; t < shard_.triangle_count_; ++t)
    for (int k = 0; k < 3; ++k)
      if (shard_.corner(t, k) >= shard_.vertex_count_)
        in_.fail("corner " + std::to_string(k) + " of triangle " + std::to_string(t),
                 shard_.corner(t, k), "vertex_count is " + std::to_string(shard_.vertex_count_));
}

void Shard::Decoder::read_ids_and_parts() {
  namespace sf = shard_format;
  const std::uint32_t triangle_count = shard_.triangle_count_;
  if (id_bytes_ == 4)
    in_.array(shard_.id_offsets32_, begin_of(sf::ids), end_of(sf::ids), triangle_count, "ids");
  else
    in_.array(shard_.id_offsets64_, begin_of(sf::ids), end_of(sf::ids), triangle_count, "ids");
  in_.array(shard_.part_palette_, begin_of(sf::part_palette), end_of(sf::part_palette), part_count_,
            "part_palette");
  in_.array(shard_.part_indices_, begin_of(sf::part_indices), end_of(sf::part_indices),
            std::uint64_t(triangle_count) * part_index_bytes_, "part_indices");
  // One loop per index width: a copy of a variable width per triangle was an eighth of decode.
  auto check_part_indices = [&]<class Index>() {
    for (std::uint32_t t = 0; t < triangle_count; ++t) {
      Index i = 0;
      std::memcpy(&i, shard_.part_indices_.data() + std::size_t(t) * sizeof(Index), sizeof(Index));
      if (i >= part_count_)
        in_.fail("part index of triangle " + std::to_string(t), std::uint32_t(i),
                 "part_count is " + std::to_string(part_count_));
    }
  };
  if (part_index_bytes_ == 1) check_part_indices.template operator()<std::uint8_t>();
  if (part_index_bytes_ == 2) check_part_indices.template operator()<std::uint16_t>();
  if (part_index_bytes_ == 4) check_part_indices.template operator()<std::uint32_t>();
}

void Shard::Decoder::check_grid_axes(std::uint64_t& cells) const {
  cells = 1;
  for (int k = 0; k < 3; ++k) {
    const std::uint32_t n = shard_.grid_cells_[k];
    if (n == 0) in_.fail("grid cells along axis " + std::to_string(k), 0, "at least 1");
    cells *= n;  // < 2^96 cannot overflow before the check below stops it
    if (cells > structure_count_)
      in_.fail("grid cell count", cells,
               "the product of cells per axis must equal structure_count " +
                   std::to_string(structure_count_));
    if (!(std::isfinite(shard_.grid_lo_[k]) && std::isfinite(shard_.grid_cell_size_[k]) &&
          shard_.grid_cell_size_[k] > 0 && std::isfinite(shard_.grid_boundary(k, n))))
      in_.fail(
          "grid lo / cell size along axis " + std::to_string(k),
          std::to_string(shard_.grid_lo_[k]) + " / " + std::to_string(shard_.grid_cell_size_[k]),
          "finite, with a positive cell size");
    if (!(shard_.grid_boundary(k, 0) <= shard_.bounds_.lo[k] &&
          shard_.bounds_.hi[k] <= shard_.grid_boundary(k, n)))
      in_.fail("grid extent along axis " + std::to_string(k),
               std::to_string(shard_.grid_boundary(k, 0)) + ".." +
                   std::to_string(shard_.grid_boundary(k, n)),
               "must hold every stored vertex");
  }
  if (cells != structure_count_)
    in_.fail("grid cell count", cells,
             "must equal structure_count " + std::to_string(structure_count_));
}

void Shard::Decoder::read_grid() {
  namespace sf = shard_format;
  std::uint64_t cells = 0;
  check_grid_axes(cells);
  if (reference_bytes_ != (shard_.triangle_count_ <= 65536 ? 2 : 4))
    in_.fail("reference_bytes", unsigned(reference_bytes_),
             "2 when triangle_count <= 65536, else 4");
  std::pmr::vector<std::uint32_t>& offsets = shard_.cell_offsets_;
  in_.array(offsets, begin_of(sf::structure), end_of(sf::structure), cells + 1, "structure");
  if (offsets[0] != 0) in_.fail("offset of cell 0", offsets[0], "0");
  for (std::uint64_t c = 0; c < cells; ++c)
    if (offsets[c + 1] < offsets[c])
      in_.fail("offset of cell " + std::to_string(c + 1), offsets[c + 1],
               "offsets must not decrease; the previous is " + std::to_string(offsets[c]));
  if (offsets[cells] != reference_count_)
    in_.fail("last cell offset", offsets[cells],
             "must equal reference_count " + std::to_string(reference_count_));
  read_grid_references();
}

void Shard::Decoder::read_grid_references() {
  namespace sf = shard_format;
  if (reference_bytes_ == 2)
    in_.array(shard_.references16_, begin_of(sf::references), end_of(sf::references),
              reference_count_, "references");
  else
    in_.array(shard_.references32_, begin_of(sf::references), end_of(sf::references),
              reference_count_, "references");
  for (std::uint32_t r = 0; r < reference_count_; ++r) {
    const std::uint32_t t =
        reference_bytes_ == 2 ? shard_.references16_[r] : shard_.references32_[r];
    if (t >= shard_.triangle_count_)
      in_.fail("reference " + std::to_string(r), t,
               "triangle_count is " + std::to_string(shard_.triangle_count_));
  }
}

/// What the R-tree's nodes must agree on, gathered as they are read.
struct Shard::Decoder::RtreeChecks {
  RtreeChecks(std::uint32_t nodes, std::uint32_t triangles, bool check_boxes)
      : relative(thread_relative()), depth(nodes, 0), has_parent(nodes, 0), covered(triangles, 0) {
    relative.resize(6 * std::size_t(nodes));
    if (check_boxes) boxes.resize(nodes);
  }
  // Reused by the thread's decodes (converted to floats in one pass after the nodes' loop).
  static std::vector<double>& thread_relative() {
    thread_local std::vector<double> relative;
    return relative;
  }
  std::vector<double>& relative;     ///< the stored coordinates by axis, lo then hi
  std::vector<geometry::Box> boxes;  ///< in double, for the enclosure checks
  std::vector<std::uint32_t> depth;
  std::vector<std::uint8_t> has_parent;
  std::vector<std::uint8_t> covered;  ///< triangles in a leaf read so far
  std::uint64_t leaf_triangles = 0;
};

void Shard::Decoder::read_rtree() {
  namespace sf = shard_format;
  if (reference_count_ != 0 || reference_bytes_ != 0)
    in_.fail("reference_count / reference_bytes of an R-tree",
             std::to_string(reference_count_) + " / " + std::to_string(reference_bytes_), "0");
  if (structure_count_ == 0) in_.fail("R-tree node count", 0, "at least the root");
  const std::size_t record = sf::node_record_bytes(shard_.precision_);
  const std::size_t begin = begin_of(sf::structure);
  if (std::uint64_t(structure_count_) > (end_of(sf::structure) - begin) / record)
    in_.fail("R-tree node count", structure_count_,
             "the structure section holds " + std::to_string(end_of(sf::structure) - begin) +
                 " bytes of " + std::to_string(record) + "-byte nodes");
  shard_.nodes_.resize(structure_count_);
  shard_.node_stride_ = std::size_t(structure_count_) + kNodeBoxPadding;
  // The padding holds empty boxes (never read into a result: children past a node's count
  // are masked off).
  shard_.node_boxes_.assign(6 * shard_.node_stride_, 0.0f);
  RtreeChecks checks(structure_count_, shard_.triangle_count_, check_boxes_);
  for (std::uint32_t i = 0; i < structure_count_; ++i)
    read_rtree_node(i, begin + std::size_t(i) * record, checks);
  round_node_boxes_outward(checks.relative);
  if (checks.leaf_triangles != shard_.triangle_count_)
    in_.fail("triangles in R-tree leaves", checks.leaf_triangles,
             "must equal triangle_count " + std::to_string(shard_.triangle_count_));
  if (check_boxes_) check_parents_enclose_children(checks.boxes);
}

void Shard::Decoder::read_rtree_node(std::uint32_t i, std::size_t at, RtreeChecks& checks) {
  namespace sf = shard_format;
  const std::size_t record = sf::node_record_bytes(shard_.precision_);
  const bool float32 = shard_.precision_ == StoredPrecision::float32;
  Node& node = shard_.nodes_[i];
  geometry::Box box;
  for (int k = 0; k < 3; ++k) {
    const double lo = float32 ? double(in_.at<float>(at + 4 * k)) : in_.at<double>(at + 8 * k);
    const double hi =
        float32 ? double(in_.at<float>(at + 12 + 4 * k)) : in_.at<double>(at + 24 + 8 * k);
    box.lo[k] = shard_.origin_[k] + lo;
    box.hi[k] = shard_.origin_[k] + hi;
    checks.relative[k * structure_count_ + i] = lo;
    checks.relative[(3 + k) * structure_count_ + i] = hi;
  }
  node.first = in_.at<std::uint32_t>(at + record - 8);
  node.count = in_.at<std::uint32_t>(at + record - 4);
  if (!finite(box.lo) || !finite(box.hi))
    in_.fail("box of R-tree node", i, "its coordinates are not finite");
  if (check_boxes_) checks.boxes[i] = box;
  if (i > 0 && !checks.has_parent[i]) in_.fail("R-tree node", i, "no node lists it as a child");
  const std::uint32_t count = node.count & ~sf::kLeafFlag;
  const std::uint32_t triangle_count = shard_.triangle_count_;
  if (node.count & sf::kLeafFlag) {
    if (count == 0 || node.first > triangle_count || count > triangle_count - node.first)
      in_.fail("triangle range of R-tree leaf " + std::to_string(i),
               std::to_string(node.first) + "+" + std::to_string(count),
               "non-empty, within triangle_count " + std::to_string(triangle_count));
    for (std::uint32_t t = node.first; t < node.first + count; ++t) {
      if (checks.covered[t]) in_.fail("triangle " + std::to_string(t), "", "in two R-tree leaves");
      checks.covered[t] = 1;
      if (check_boxes_)
        for (int k = 0; k < 3; ++k)
          if (!geometry::box_contains(box, stored_[shard_.corner(t, k)]))
            in_.fail("box of R-tree leaf " + std::to_string(i), "",
                     "does not enclose its triangle " + std::to_string(t));
    }
    checks.leaf_triangles += count;
    return;
  }
  if (count == 0 || count > sf::kMaxFanout || node.first <= i || node.first > structure_count_ ||
      count > structure_count_ - node.first)
    in_.fail("children of R-tree node " + std::to_string(i),
             std::to_string(node.first) + "+" + std::to_string(count),
             "1.." + std::to_string(sf::kMaxFanout) + " nodes after it, within " +
                 std::to_string(structure_count_));
  if (checks.depth[i] + 1 >= sf::kMaxDepth)
    in_.fail("depth of R-tree node " + std::to_string(i), checks.depth[i] + 1,
             "at most " + std::to_string(sf::kMaxDepth - 1));
  for (std::uint32_t c = node.first; c < node.first + count; ++c) {
    if (checks.has_parent[c]) in_.fail("R-tree node", c, "listed as a child twice");
    checks.has_parent[c] = 1;
    checks.depth[c] = checks.depth[i] + 1;
  }
}

void Shard::Decoder::round_node_boxes_outward(const std::vector<double>& relative) {
  // Rounded outward by a float's unit in the last place (at least; values near zero by the
  // smallest normal float: a subnormal operand costs a microcode assist, which made decode
  // of a float32 R-tree a quarter slower), clamped to the finite floats.
  constexpr double kMost = std::numeric_limits<float>::max();
  constexpr float kTiny = std::numeric_limits<float>::min();
  double largest = 0;
  for (std::size_t k = 0; k < 6; ++k) {
    const double* from = relative.data() + k * structure_count_;
    float* to = shard_.node_boxes_.data() + k * shard_.node_stride_;
    const float side = k < 3 ? -1.0f : 1.0f;
    for (std::uint32_t i = 0; i < structure_count_; ++i) {
      largest = std::max(largest, std::fabs(from[i]));
      const float f = float(std::clamp(from[i], -kMost, kMost));
      to[i] = std::clamp(f + side * (std::fabs(f) * 0x1p-23f + kTiny), -float(kMost), float(kMost));
    }
  }
  shard_.clamped_node_boxes_ = largest > kMost;
}

void Shard::Decoder::check_parents_enclose_children(const std::vector<geometry::Box>& boxes) const {
  // Checked after every box is read.
  for (std::uint32_t i = 0; i < structure_count_; ++i) {
    const Node& node = shard_.nodes_[i];
    if (node.count & shard_format::kLeafFlag) continue;
    for (std::uint32_t c = node.first; c < node.first + node.count; ++c)
      if (!box_contains_box(boxes[i], boxes[c]))
        in_.fail("box of R-tree node " + std::to_string(i), "",
                 "does not enclose its child " + std::to_string(c));
  }
}

Shard Shard::decode(std::span<const std::byte> payload, std::string_view context,
                    DecodeChecks checks, std::pmr::memory_resource* memory) {
  Shard shard(memory != nullptr ? memory : std::pmr::get_default_resource());
  Decoder decoder(payload, context, checks, shard);
  decoder.read_header();
  decoder.read_section_offsets();
  decoder.read_vertices();
  decoder.read_triangles();
  decoder.read_ids_and_parts();
  if (shard.kind_ == ShardKind::grid)
    decoder.read_grid();
  else
    decoder.read_rtree();
  return shard;
}

}  // namespace tetrapage
