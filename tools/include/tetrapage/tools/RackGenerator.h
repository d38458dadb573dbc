#pragma once
/// @file RackGenerator.h
/// A benchmark assembly built from real CAD parts: STEP files (KiCad's 3D packages, say) laid
/// out on printed-circuit boards, a few board types instanced upright in card cages, written
/// as manifests in millimetres (docs/USAGE.md, `tetrapage generate rack`).
///
/// Frames: a board's own frame has its plate in [0, length] x [0, width] x [0, thickness],
/// parts standing on z = thickness. The rack stands boards upright: board (u, v, w) goes to
/// rack (w + slot * pitch, u + rack * (length + rack_gap), v + cage * (width + cage_gap)).

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "tetrapage/formats/base/Progress.h"
#include "tetrapage/formats/mesh/CadReader.h"
#include "tetrapage/formats/mesh/Manifest.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/tools/Random.h"

namespace tetrapage {

/// A STEP file as the generator learned it by tessellating it once.
struct RackPart {
  std::filesystem::path file;  ///< absolute
  std::string name;            ///< the file's stem
  BoundingBox box;             ///< in its own frame, millimetres
  std::uint64_t triangles = 0;
};

/// Which files of a folder become parts.
struct RackPartOptions {
  std::filesystem::path folder;
  std::size_t count = 48;                 ///< distinct parts wanted
  std::uint64_t max_file_bytes = 400000;  ///< larger files are passed over (reading stays fast)
  double max_height = 12.0;               ///< mm; taller parts would not fit between boards
  double max_side = 60.0;                 ///< mm; the longest side of a footprint
  std::uint64_t seed = 1;
  TessellationOptions tessellation;
};

struct RackPartLibrary {
  std::vector<RackPart> parts;       ///< in draw order
  std::vector<std::string> skipped;  ///< "file: reason", for files read and not used
  std::size_t candidates = 0;        ///< STEP files under the size cap
};

/// Every .step/.stp file under options.folder (recursively, in path order) below the size cap,
/// drawn in a seeded order and read (read_cad) until options.count fit; unreadable, too tall or
/// too wide files are skipped with their reason.
/// @throw IoError if the folder cannot be listed; InputError if no part fits.
RackPartLibrary load_rack_parts(const RackPartOptions& options,
                                Progress& progress = Progress::silent());

/// Reads one STEP file as a part (its triangles and box). @throw as read_cad.
RackPart read_rack_part(const std::filesystem::path& file, const TessellationOptions& tessellation);

/// The printed-circuit board every board type shares.
struct BoardOptions {
  double length = 160.0, width = 100.0, thickness = 1.6;  ///< mm
  double gap = 0.5;  ///< mm kept free between footprints and from the plate's edges
};

/// A part put on a board: part index, quarter turns about z, and where its box ends up.
struct PlacedPart {
  std::size_t part = 0;
  int quarter_turns = 0;
  Transform transform;  ///< part frame -> board frame
  BoundingBox box;      ///< the part's box placed (exact: a quarter turn and a translation)
};

struct BoardLayout {
  std::vector<PlacedPart> parts;
  std::uint64_t triangles = 0;  ///< the parts' and the plate's
};

/// Shelf packing on the plate: parts drawn at random (a quarter turn each) fill rows along x,
/// a new row opened above the tallest footprint of the last; `first` (if any) is placed before
/// the draws. Stops after 32 draws in a row that fit nowhere. Boxes are pairwise disjoint, at
/// least options.gap apart and from the edges, standing on the plate.
BoardLayout layout_board(std::span<const RackPart> parts, const BoardOptions& options,
                         Random& random, const RackPart* first = nullptr);

/// The rack around the boards.
struct RackOptions {
  RackPartOptions parts;
  BoardOptions board;
  std::uint64_t triangles = 1000000;  ///< boards are added until the rack holds this many
  std::size_t board_types = 4;
  double pitch = 20.32;             ///< mm between the plates of neighbouring slots (4 HP)
  std::size_t slots = 16;           ///< boards per card cage
  std::size_t cages = 6;            ///< cages stacked in one rack
  double cage_gap = 30.0;           ///< mm between stacked cages
  double rack_gap = 100.0;          ///< mm between racks standing side by side
  bool flat = false;                ///< one manifest of mesh entries instead of rack -> boards
  std::filesystem::path connector;  ///< a header put on every board type (optional)
  std::filesystem::path plug;       ///< the flying part inserted into a header (insertion_board)
  std::size_t insert_steps = 200;   ///< poses of the insertion flight
  double insert_depth = 6.0;        ///< mm the plug travels past the header's top
};

struct RackSummary {
  std::size_t boards = 0;
  std::uint64_t triangles = 0;
  BoundingBox bounds;  ///< of the boards' boxes, rack frame
  std::vector<BoardLayout> types;
  RackPartLibrary library;
  std::vector<Transform> board_placements;  ///< board frame -> rack frame, in board order
  std::filesystem::path insertion_poses;    ///< empty without connector and plug
  std::uint64_t plug_triangles = 0;
};

/// The box of `box`'s corners placed by `m`; for a quarter turn about z and a translation, the
/// box of the placed vertices themselves (each coordinate is one negated or not, plus a term).
BoundingBox placed_box(const BoundingBox& box, const Transform& m);

/// Board i's placement in the rack (board frame -> rack frame).
Transform board_placement(const RackOptions& options, std::size_t board);

/// Generates the rack: parts, board types, as many boards as the triangle target asks (types
/// in turn), written as `output` (the rack manifest) with its board manifests and plate mesh in
/// OUTPUT_STEM-boards/ beside it; with connector and plug, the insertion flight (insertion_board)
/// as OUTPUT_STEM-insert.csv. The same options and parts give the same bytes.
/// @throw InputError for a bad option or parts that do not fit; IoError on a write failure.
RackSummary generate_rack(const RackOptions& options, const std::filesystem::path& output,
                          Progress& progress = Progress::silent());

/// The board whose header the plug goes into: the last of the first cage, whose parts' side
/// faces the open end of the cage (between two boards a plug has no room).
std::size_t insertion_board(const RackOptions& options, std::size_t boards);

/// The plug's poses (rack frame), turned over and moved straight along the normal of `board`
/// from 5 mm above `header` (its box in the board's frame) to options.insert_depth below its top.
std::vector<Pose> insertion_flight(const RackOptions& options, std::size_t board,
                                   const BoundingBox& header, const RackPart& plug);

}  // namespace tetrapage
