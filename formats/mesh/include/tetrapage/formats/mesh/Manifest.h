#pragma once
/// @file Manifest.h
/// Assembly manifests (JSON): parts, each a mesh file or a sub-assembly (another manifest)
/// placed one or more times.
///
/// {
///   "units": "mm",                              // the assembly's unit (default "m")
///   "parts": [
///     { "name": "bracket", "file": "bracket.stl", "units": "in",
///       "instances": [ { "translation": [0,0,0], "rotation": [1,0,0,0], "scale": 1 },
///                      { "matrix": [16 numbers, row-major 4x4, last row 0 0 0 1] } ] },
///     { "file": "frame.obj" },                  // no instances: placed once, identity
///     { "name": "board", "manifest": "board.json", "instances": [ ... ] }
///   ]
/// }
/// File paths are relative to the folder of the manifest naming them. rotation is a quaternion
/// qw,qx,qy,qz (normalised on read); scale a number or three; an instance maps x to R (S x) + t.
/// Instance transforms are in the unit of the manifest holding them.
///
/// Units: a mesh part's own "units" scale it into its manifest's unit; without them, a unit the
/// file itself declares (ReadReport::length_unit: STEP, IGES) is converted instead, and a file
/// that declares none is taken to be in the manifest's unit. A given "units" wins over the
/// file's. A sub-assembly ("manifest" instead of "file"; no "units" of its own) is in its
/// manifest's "units" (default "m", whoever includes it), converted into the including one's.
///
/// "name" defaults to the file's stem and must be unique in its manifest. Sub-assemblies nest
/// up to 64 manifests deep; a manifest that includes itself, directly or not, is refused, and an
/// assembly places at most 2^24 mesh instances in all. Comments (// and /* */) are allowed;
/// unknown fields are errors (they are usually typos).

#include <array>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "tetrapage/formats/base/Progress.h"
#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/formats/mesh/CadReader.h"

namespace tetrapage {

/// Row-major 4x4 affine transform (the last row must be 0 0 0 1).
using Transform = std::array<double, 16>;
/// The 4x4 identity.
Transform identity_transform();
/// a b (b applied first), both affine.
Transform compose_transforms(const Transform& a, const Transform& b);
/// (m0 sx + m1 sy + m2 sz) + m3 per row, in double without fused multiply-adds: the placement
/// every loader uses, so that one point placed by one transform gives the same bits anywhere.
Vec3 apply_transform(const Transform& m, const Vec3& s);
/// The largest factor by which `m` stretches a length (its linear part's largest column norm).
double largest_stretch(const Transform& m);

struct Manifest;

struct ManifestPart {
  std::string name;
  std::filesystem::path file;  ///< a mesh (absolute, or relative to the working folder); empty
                               ///< for a sub-assembly
  std::shared_ptr<const Manifest> assembly;  ///< a sub-assembly; null for a mesh file
  /// Part units -> its manifest's units; for a sub-assembly, the sub-manifest's units -> ours.
  double unit_scale = 1.0;
  bool units_given = false;          ///< "units" was given (it wins over the file's own unit)
  std::vector<Transform> instances;  ///< at least one
};

struct Manifest {
  std::filesystem::path path;
  std::string units = "m";
  std::vector<ManifestPart> parts;
};

/// Metres per unit for "m", "cm", "mm", "um", "in", "ft".
/// @throw InputError for an unknown unit name.
double metres_per_unit(const std::string& unit);

/// Whether `path` names a manifest rather than a mesh: a ".json" extension, in any case.
bool is_manifest_path(const std::filesystem::path& path);

/// The factor taking a mesh part's coordinates, as its reader returned them (in `file_unit`,
/// ReadReport::length_unit, empty when the file does not say), into the unit `manifest_units`
/// of the manifest naming it: the part's own "units" when given, else the file's unit, else 1.
/// @throw InputError naming the part's file when `file_unit` is not a unit metres_per_unit knows.
double part_unit_scale(const ManifestPart& part, const std::string& manifest_units,
                       const std::string& file_unit);

/// Parses a manifest and, through "manifest" entries, its sub-assemblies (each file read once).
/// @throw IoError (a sub-manifest that cannot be read names the including file and field),
///        FormatError (bad JSON, names the file and the JSON path of the bad field), InputError
///        (unknown unit, non-finite or singular transform; a cycle of manifests or nesting
///        beyond 64, naming the chain of files; more than 2^24 mesh instances).
Manifest read_manifest(const std::filesystem::path& path);

/// Reads the file of each mesh entry once (an entry reached through two sub-assembly entries
/// counts twice) and places all its instances, sub-assemblies expanded; one soup part per
/// placed instance (one per node for a file of several parts, glTF).
/// Order: the mesh entries depth first through the manifests, and for each, its placements with
/// the outer sub-assembly's instance varying slowest. Names: part_names is the entry's "name"
/// (or the node's name in a file of several parts); part_paths the instance path from the top,
/// "rack/board#3/U7": an entry's name, with "#k" (k = its index in "instances") when it is
/// placed more than once, and "/node" for a node. Placement composes the transforms from the
/// top down in double (units folded in) and computes (m0 sx + m1 sy + m2 sz) + m3 per row,
/// s = part_unit_scale * x; a top-level part's instance is used as given (identity and integer
/// translations stay exact). Triangles that rounding flattens are dropped and counted in the
/// file's report. Reports (one per file read) are appended to `reports` if given; `progress`
/// advances by one per file.
/// @throw as read_mesh (IoError, FormatError, InputError); InputError if a placement
///        overflows, a file's unit is unknown, or the assembly has more than 2^32-1 vertices.
TriangleSoup load_assembly(const Manifest& manifest, std::vector<ReadReport>* reports = nullptr,
                           Progress& progress = Progress::silent(),
                           const TessellationOptions& tessellation = {});

/// One piece of a list of inputs, loadable on its own: a mesh file, or one mesh entry of a
/// manifest (reached through its sub-assemblies) with all its placements. Loading the pieces
/// in order and appending them gives the soup load_inputs gives, triangle for triangle, while
/// holding one piece (one file, placed) at a time.
struct InputPiece {
  std::filesystem::path input;
  std::shared_ptr<const Manifest> manifest;  ///< the top manifest; null for a mesh file
  /// The mesh entry: parts[entries[0]] of the top manifest, then parts[entries[1]] of that
  /// sub-assembly, and so on.
  std::vector<std::size_t> entries;

  /// The mesh file the piece reads.
  const std::filesystem::path& file() const;
  /// How many times the file is placed (the instances along the entries, multiplied).
  std::size_t copies() const;
};

/// The pieces of `inputs`, in order (the manifests are read here).
/// @throw as read_manifest.
std::vector<InputPiece> input_pieces(const std::vector<std::filesystem::path>& inputs);

/// Loads one piece; appends one report per file read. @throw as read_mesh and load_assembly.
TriangleSoup load_input_piece(const InputPiece& piece, std::vector<ReadReport>* reports = nullptr,
                              const TessellationOptions& tessellation = {});

/// One piece's file read once, its placements appended on demand, a batch at a time: a file
/// placed 10^6 times is read once and never held placed whole. Placing every copy in order
/// gives load_input_piece's soup, triangle for triangle.
class PieceLoader {
 public:
  /// Reads the piece's file. @throw as read_mesh; InputError for a file's unknown unit.
  explicit PieceLoader(const InputPiece& piece, const TessellationOptions& tessellation = {});
  /// The piece's file read already: `source` and `report` as read_mesh gave them.
  /// @throw InputError for the file's unknown unit, or an entry the manifest does not hold.
  PieceLoader(const InputPiece& piece, TriangleSoup source, const ReadReport& report);
  ~PieceLoader();
  PieceLoader(PieceLoader&&) noexcept;
  PieceLoader& operator=(PieceLoader&&) noexcept;

  /// How many times the file is placed (InputPiece::copies()).
  std::size_t copies() const;
  /// The file as read (its unit, no placement).
  const TriangleSoup& source() const;
  /// True for a mesh file given on its own: its only copy is source() as it is.
  bool placed_as_read() const;
  /// Appends copies [first, first + count) to `soup` (one soup part per copy, or per node), as
  /// load_assembly places them. Safe to call from several threads on different soups.
  /// @throw InputError as load_assembly (overflow, precision, too many vertices).
  void place(std::size_t first, std::size_t count, TriangleSoup& soup) const;
  /// Moves source() out (the loader then places nothing).
  TriangleSoup take_source();
  /// The file's report: the reader's, plus the triangles the placements so far dropped and,
  /// for a tessellated file, its deflection in the top manifest's unit over those placements.
  ReadReport report() const;

 private:
  PieceLoader(const InputPiece& piece, std::pair<TriangleSoup, ReadReport> read);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// A placement of a piece whose file is read in chunks (read_mesh_in_chunks): each chunk placed
/// as PieceLoader::place places the whole file, so that the placed chunks, in order, are that
/// copy's placed soup triangle for triangle.
class PlacedChunks {
 public:
  /// Placement `copy` (< piece.copies()) of a piece a manifest places, whose file states the
  /// unit `file_unit` ("" for none, as the mesh formats; "mm" for STEP and IGES).
  /// @throw InputError for an entry the manifest does not hold, or an unknown unit.
  PlacedChunks(const InputPiece& piece, std::size_t copy, const std::string& file_unit = {});
  ~PlacedChunks();
  PlacedChunks(const PlacedChunks&) = delete;
  PlacedChunks& operator=(const PlacedChunks&) = delete;

  /// Notes a vertex of the file as it is read (SoupChunks::on_vertex), used or not: the whole
  /// placement places every vertex and checks its precision over all of them.
  /// @throw InputError for a vertex placed beyond the accepted coordinates.
  void note_vertex(const Vec3& vertex);
  /// Moves the chunk's vertices where the placement puts them and drops the triangles that
  /// rounding flattens (counted by dropped()). Its parts stay the file's.
  /// @throw InputError for a vertex placed beyond the accepted coordinates.
  void place(TriangleSoup& chunk);
  /// After the last chunk: the placed part's precision checked over the box of every vertex
  /// noted; returns the
  /// parts of the placement (part_names, part_paths) for the file's parts `file_parts`.
  /// @throw InputError for a part placed too far from the origin for its size.
  TriangleSoup finish(const TriangleSoup& file_parts);
  /// The triangles the placement flattened and dropped so far.
  std::uint64_t dropped() const;
  /// What the placement scales lengths by at most (a tessellation's deflection, from the
  /// file's unit to the top manifest's).
  double largest_scale() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Loads inputs that are mesh files or manifests (.json), in order, into one soup (parts
/// appended in order, indices shifted).
/// @throw as read_mesh, read_manifest and load_assembly.
TriangleSoup load_inputs(const std::vector<std::filesystem::path>& inputs,
                         std::vector<ReadReport>* reports = nullptr,
                         Progress& progress = Progress::silent(),
                         const TessellationOptions& tessellation = {});

}  // namespace tetrapage
