#include "tetrapage/tools/RackGenerator.h"

#include <algorithm>
#include <cctype>
#include <cstdio>

#include "tetrapage/formats/base/Error.h"

namespace tetrapage {
namespace {

constexpr int kMissesBeforeFull = 32;

std::string lower_extension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

std::string millimetres(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g mm", value);
  return text;
}

/// The STEP files under `folder` no larger than `max_bytes`, in path order.
std::vector<std::filesystem::path> step_files(const std::filesystem::path& folder,
                                              std::uint64_t max_bytes) {
  std::error_code ec;
  std::filesystem::recursive_directory_iterator it(folder, ec), end;
  if (ec) throw IoError("cannot list parts folder '" + folder.string() + "': " + ec.message());
  std::vector<std::filesystem::path> files;
  for (; it != end; it.increment(ec)) {
    if (ec) throw IoError("cannot list parts folder '" + folder.string() + "': " + ec.message());
    const std::string ext = lower_extension(it->path());
    if ((ext != ".step" && ext != ".stp") || !it->is_regular_file(ec)) continue;
    if (it->file_size(ec) <= max_bytes && !ec)
      files.push_back(std::filesystem::absolute(it->path()));
  }
  std::sort(files.begin(), files.end());
  return files;
}

/// Why `part` cannot go on a board, or nothing.
std::string unfit_reason(const RackPart& part, const RackPartOptions& options) {
  const Vec3 size = part.box.size();
  if (size[2] > options.max_height)
    return "height " + millimetres(size[2]) + " over " + millimetres(options.max_height);
  if (std::max(size[0], size[1]) > options.max_side)
    return "footprint side " + millimetres(std::max(size[0], size[1])) + " over " +
           millimetres(options.max_side);
  return {};
}

/// (x, y) turned by q quarter turns about z: exact (negations and swaps only).
Vec3 quarter_turn(const Vec3& p, int q) {
  switch (q & 3) {
    case 1:
      return {-p[1], p[0], p[2]};
    case 2:
      return {-p[0], -p[1], p[2]};
    case 3:
      return {p[1], -p[0], p[2]};
    default:
      return p;
  }
}

BoundingBox turned_box(const BoundingBox& box, int q) {
  BoundingBox out;
  out.extend(quarter_turn(box.lo, q));
  out.extend(quarter_turn(box.hi, q));
  out.extend(quarter_turn({box.lo[0], box.hi[1], box.lo[2]}, q));
  out.extend(quarter_turn({box.hi[0], box.lo[1], box.hi[2]}, q));
  return out;
}

/// The quarter turn q, then the translation putting the turned box's low corner at `corner`.
Transform quarter_turn_placement(const BoundingBox& box, int q, const Vec3& corner) {
  const BoundingBox turned = turned_box(box, q);
  Transform m = identity_transform();
  const Vec3 ex = quarter_turn({1, 0, 0}, q), ey = quarter_turn({0, 1, 0}, q);
  for (int row = 0; row < 3; ++row) {
    m[4 * row] = ex[row];
    m[4 * row + 1] = ey[row];
    m[4 * row + 3] = corner[row] - turned.lo[row];
  }
  return m;
}

/// Rows of shelves filled along x, each as deep (along y) as its deepest footprint.
class ShelfPacker {
 public:
  explicit ShelfPacker(const BoardOptions& board) : board_(board), x_(board.gap), y_(board.gap) {}

  /// Where a footprint of `size` goes (its low corner), or false when it fits nowhere.
  bool place(const Vec3& size, double& x, double& y) {
    const double right = board_.length - board_.gap, top = board_.width - board_.gap;
    if (board_.gap + size[0] > right || board_.gap + size[1] > top) return false;
    if (x_ + size[0] > right) {
      y_ += shelf_ + board_.gap;
      x_ = board_.gap;
      shelf_ = 0;
    }
    if (y_ + size[1] > top) return false;
    x = x_;
    y = y_;
    x_ += size[0] + board_.gap;
    shelf_ = std::max(shelf_, size[1]);
    return true;
  }

 private:
  BoardOptions board_;
  double x_, y_, shelf_ = 0;
};

bool put(BoardLayout& layout, ShelfPacker& packer, const RackPart& part, std::size_t index, int q,
         double thickness) {
  double x = 0, y = 0;
  if (!packer.place(turned_box(part.box, q).size(), x, y)) return false;
  PlacedPart placed{index, q, quarter_turn_placement(part.box, q, {x, y, thickness}), {}};
  placed.box = placed_box(part.box, placed.transform);
  layout.parts.push_back(placed);
  layout.triangles += part.triangles;
  return true;
}

}  // namespace

BoundingBox placed_box(const BoundingBox& box, const Transform& m) {
  BoundingBox out;
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 s{(corner & 1) ? box.hi[0] : box.lo[0], (corner & 2) ? box.hi[1] : box.lo[1],
                 (corner & 4) ? box.hi[2] : box.lo[2]};
    out.extend(apply_transform(m, s));
  }
  return out;
}


RackPart read_rack_part(const std::filesystem::path& file,
                        const TessellationOptions& tessellation) {
  const TriangleSoup soup = read_cad(file, tessellation);
  return {std::filesystem::absolute(file), file.stem().string(), soup.bounds(),
          soup.triangle_count()};
}

RackPartLibrary load_rack_parts(const RackPartOptions& options, Progress& progress) {
  if (options.count == 0) throw InputError("generate rack: --parts must be at least 1");
  RackPartLibrary library;
  const std::vector<std::filesystem::path> files =
      step_files(options.folder, options.max_file_bytes);
  library.candidates = files.size();
  Random random(options.seed);
  for (std::uint32_t i : random_subset(files.size(), files.size(), random)) {
    if (library.parts.size() == options.count) break;
    RackPart part;
    try {
      part = read_rack_part(files[i], options.tessellation);
    } catch (const Error& e) {  // a file OCCT cannot read is passed over, as asked
      library.skipped.push_back(files[i].string() + ": " + e.what());
      continue;
    }
    if (const std::string reason = unfit_reason(part, options); !reason.empty()) {
      library.skipped.push_back(files[i].string() + ": " + reason);
      continue;
    }
    library.parts.push_back(std::move(part));
    progress.advance();
  }
  if (library.parts.empty())
    throw InputError("generate rack: no STEP file under '" + options.folder.string() +
                     "' of at most " + std::to_string(options.max_file_bytes) +
                     " bytes was read and fits a board (" + std::to_string(files.size()) +
                     " candidates)");
  return library;
}

BoardLayout layout_board(std::span<const RackPart> parts, const BoardOptions& options,
                         Random& random, const RackPart* first) {
  if (!(options.length > 2 * options.gap && options.width > 2 * options.gap &&
        options.thickness > 0 && options.gap >= 0))
    throw InputError("generate rack: the board " + millimetres(options.length) + " x " +
                     millimetres(options.width) + " x " + millimetres(options.thickness) +
                     " with gaps of " + millimetres(options.gap) + " has no room for parts");
  BoardLayout layout;
  layout.triangles = 12;  // the plate
  ShelfPacker packer(options);
  if (first != nullptr && !put(layout, packer, *first, parts.size(), 0, options.thickness))
    throw InputError("generate rack: the connector '" + first->file.string() +
                     "' does not fit on the board");
  for (int misses = 0; misses < kMissesBeforeFull && !parts.empty();) {
    const std::size_t p = random.below(parts.size());
    const int q = static_cast<int>(random.below(4));
    misses = put(layout, packer, parts[p], p, q, options.thickness) ? 0 : misses + 1;
  }
  return layout;
}

Transform board_placement(const RackOptions& options, std::size_t board) {
  const std::size_t per_rack = options.slots * options.cages;
  const double slot = double(board % options.slots);
  const double cage = double(board / options.slots % options.cages);
  const double rack = double(board / per_rack);
  // Upright: the plate's normal along x, its length along y, its width up.
  return {0, 0, 1, slot * options.pitch,
          1, 0, 0, rack * (options.board.length + options.rack_gap),
          0, 1, 0, cage * (options.board.width + options.cage_gap),
          0, 0, 0, 1};
}

}  // namespace tetrapage
