#pragma once
/// @file Manifest.h
/// Assembly manifests (JSON): parts, each a mesh file placed one or more times.
///
/// {
///   "units": "mm",                              // the assembly's unit (default "m")
///   "parts": [
///     { "name": "bracket", "file": "bracket.stl", "units": "in",
///       "instances": [ { "translation": [0,0,0], "rotation": [1,0,0,0], "scale": 1 },
///                      { "matrix": [16 numbers, row-major 4x4, last row 0 0 0 1] } ] },
///     { "file": "frame.obj" }                   // no instances: placed once, identity
///   ]
/// }
/// File paths are relative to the manifest's folder. rotation is a quaternion qw,qx,qy,qz
/// (normalised on read); scale a number or three; an instance maps x to R (S x) + t. A part's
/// own "units" scale it into the assembly's unit first; instance transforms are in the
/// assembly's unit. "name" defaults to the file's stem and must be unique. Comments (// and
/// /* */) are allowed; unknown fields are errors (they are usually typos).

#include <array>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "tetrapage/formats/CadReader.h"
#include "tetrapage/formats/Progress.h"
#include "tetrapage/formats/TriangleSoup.h"

namespace tetrapage {

/// Row-major 4x4 affine transform (the last row must be 0 0 0 1).
using Transform = std::array<double, 16>;
/// The 4x4 identity.
Transform identity_transform();

struct ManifestPart {
  std::string name;
  std::filesystem::path file;        ///< absolute, or relative to the working folder
  double unit_scale = 1.0;           ///< part units -> assembly units
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

/// Parses a manifest. @throw IoError, FormatError (bad JSON, names the file and the JSON
/// path of the bad field), InputError (unknown unit, non-finite or singular transform).
Manifest read_manifest(const std::filesystem::path& path);

/// Reads every part file once and places each instance; one soup part per instance, named
/// "name" for a single instance or "name#k" (k = 0, 1, ... the index in "instances"); a file
/// of several parts (glTF nodes) gives "name/node" or "name#k/node". Placement computes
/// (m0 sx + m1 sy + m2 sz) + m3 per row in double, s = unit_scale * x; triangles that
/// rounding flattens are dropped and counted in the file's report. Reports (one per file
/// read) are appended to `reports` if given; `progress` advances by one per file.
/// @throw as read_mesh (IoError, FormatError, InputError); InputError if a placement
///        overflows or the assembly has more than 2^32-1 vertices.
TriangleSoup load_assembly(const Manifest& manifest, std::vector<ReadReport>* reports = nullptr,
                           Progress& progress = Progress::silent(),
                           const TessellationOptions& tessellation = {});

/// One piece of a list of inputs, loadable on its own: a mesh file, or one part of a manifest
/// (with its instances placed). Loading the pieces in order and appending them gives the soup
/// load_inputs gives, triangle for triangle, while holding one piece at a time.
struct InputPiece {
  std::filesystem::path input;
  std::shared_ptr<const Manifest> manifest;  ///< null for a mesh file
  std::size_t part = 0;                      ///< the manifest's part
};

/// The pieces of `inputs`, in order (the manifests are read here).
/// @throw as read_manifest.
std::vector<InputPiece> input_pieces(const std::vector<std::filesystem::path>& inputs);

/// Loads one piece; appends one report per file read. @throw as read_mesh and load_assembly.
TriangleSoup load_input_piece(const InputPiece& piece, std::vector<ReadReport>* reports = nullptr,
                              const TessellationOptions& tessellation = {});

/// Loads inputs that are mesh files or manifests (.json), in order, into one soup (parts
/// appended in order, indices shifted).
/// @throw as read_mesh, read_manifest and load_assembly.
TriangleSoup load_inputs(const std::vector<std::filesystem::path>& inputs,
                         std::vector<ReadReport>* reports = nullptr,
                         Progress& progress = Progress::silent(),
                         const TessellationOptions& tessellation = {});

}  // namespace tetrapage
