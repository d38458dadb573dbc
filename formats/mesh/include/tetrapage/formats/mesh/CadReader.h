#pragma once
/// @file CadReader.h
/// STEP (AP203, AP214, AP242) and IGES files through OpenCASCADE's XCAF document readers: the
/// assembly tree, the names of parts and instances, the instances' placements and the length
/// unit come through; each distinct shape is tessellated once (BRepMesh_IncrementalMesh), on
/// all threads, and placed at each of its instances.

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "tetrapage/formats/base/TriangleSoup.h"

namespace tetrapage {

/// How B-rep shapes become triangles: the accuracy knob of CAD input (docs/USAGE.md).
struct TessellationOptions {
  /// The chordal deviation asked of OCCT's mesher: the largest distance between a triangle
  /// and the surface it stands for. With relative_deflection, a fraction of each shape's
  /// bounding-box diagonal; else a length in the file's coordinates as read (millimetres).
  double deflection = 0.001;
  bool relative_deflection = true;
  /// The largest angle, in radians, between the normals of the surface along a triangle's
  /// edge (OCCT's angular deflection): curved faces of small parts get enough triangles.
  double angular_deflection = 0.5;
  /// A shape that fails to tessellate is left out (and listed in the report) instead of
  /// failing the read.
  bool skip_bad_parts = false;
  /// Print progress per shape on stderr.
  bool show_progress = false;
  /// A STEP file with more product occurrences (placed components) than this is refused before
  /// it is read: OCCT's reader takes time quadratic in them (0: no limit).
  std::uint64_t max_occurrences = 10000;
  /// A file whose tessellation would have more triangles than this is refused: before the
  /// mesher runs, for a shape at a deflection finer than the default (estimated from a mesh
  /// at the default deflection), and before its instances are placed (0: no limit).
  std::uint64_t max_triangles = 20'000'000;
  /// Read and tessellate in a child process, so that OCCT's crash, hang or runaway allocation
  /// becomes an error naming the file instead of ending the caller.
  bool isolate = true;
  /// The child's memory: address space it may add to the caller's, in bytes (0: the
  /// machine's memory).
  std::uint64_t memory_limit = 0;
  /// Seconds the child may take before it is killed (0: no limit).
  double time_limit = 1800;
};

/// Sets options.deflection from `text`: a percentage of each shape's bounding-box diagonal
/// ("0.1%") or a length in millimetres ("0.01").
/// @throw InputError naming `what` (the option) and the text when it is neither, or not positive.
void set_deflection(TessellationOptions& options, const std::string& text, std::string_view what);

/// Whether `path` has a STEP (.step, .stp, .p21) or IGES (.iges, .igs) extension.
bool is_cad_path(const std::filesystem::path& path);

/// Reads a STEP or IGES file: one soup part per placed instance of a shape, named by the shape
/// (its product name, else the instance's, else the file's stem), with the instance path from
/// the file's root down ("rack/board#3/U7"; "#k" marks the k-th of siblings with one name).
/// Coordinates are in millimetres (OCCT converts from the file's unit; report.length_unit
/// says "mm"); report.tessellation_deflection is the largest absolute deflection used.
/// Triangles are in the order of the instances (depth first, as the file lists them) and, in
/// each, of the shape's faces; degenerate ones are dropped and counted.
/// @throw IoError if the file cannot be opened; FormatError if OCCT cannot read or translate
///        it (names the file); InputError for a bad option, a shape that fails to tessellate
///        (names the part; unless skip_bad_parts), or a file with no triangle.
TriangleSoup read_cad(const std::filesystem::path& path, const TessellationOptions& options = {},
                      ReadReport* report = nullptr);

}  // namespace tetrapage
