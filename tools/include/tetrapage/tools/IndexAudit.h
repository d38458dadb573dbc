#pragma once
/// @file IndexAudit.h
/// What `validate` checks against brute force (issue 4, item 8): every chosen tet holds, by
/// id, exactly the model's triangles that meet it, and every chosen shard's index returns, for
/// random boxes, exactly the stored triangles that meet the box. The oracle is CGAL's exact
/// kernel (do_intersect), sharing no code with preprocess's binning or the shard queries.

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "tetrapage/formats/base/Progress.h"
#include "tetrapage/formats/index/IndexReader.h"
#include "tetrapage/formats/mesh/Manifest.h"
#include "tetrapage/runtime/paging/Shard.h"

namespace tetrapage {

/// What the audits checked and found wrong (at most 100 problems are kept; `mismatches` counts
/// them all).
struct AuditFindings {
  std::uint64_t tets_checked = 0;
  std::uint64_t triangles_read = 0;
  std::uint64_t shards_checked = 0;
  std::uint64_t boxes_checked = 0;
  std::uint64_t mismatches = 0;
  std::vector<std::string> problems;
  void add(std::string problem);
};

/// The files an index was built from, in preprocess's order (its header's `source`: per input
/// a line "PATH_FROM_THE_INDEX_FOLDER<tab>ABSOLUTE_PATH"), each resolved against the folder of
/// `index` first (an index moved with its model still finds it), then by its absolute path; a
/// line without a tab is taken as it stands. A file found neither way is returned by its
/// absolute path, so that the caller can say it is missing.
/// @throw FormatError naming the index when the source records no input.
std::vector<std::filesystem::path> source_inputs(const IndexHeader& header, const std::filesystem::path& index);

/// The model-wide ids of the triangles a tet holds.
using StoredIds = std::function<std::vector<std::uint64_t>(std::uint32_t tet)>;

/// One triangle as a shard stores it: its model-wide id and its decoded corners.
struct StoredTriangle {
  std::uint64_t id = 0;
  std::array<Vec3, 3> corners{};
};

/// What a tet holds: the triangles of its shard, and how problems name that shard
/// ("shard 17").
struct TetContents {
  std::string shard;
  std::vector<StoredTriangle> triangles;
};
using StoredTriangles = std::function<TetContents(std::uint32_t tet)>;

/// Whether the audit compares stored coordinates with the model's as well as ids.
enum class CoordinateCheck {
  ids_only,  ///< coordinates rounded on storage (precision "float"): ids only
  exact,     ///< coordinates stored as read: each must equal the model's (0 and -0 alike)
};

/// Streams the model (the pieces of the files the index was built from, in the same order,
/// one at a time: input_pieces in Manifest.h) and checks that each tet in `tets` holds exactly the triangles that meet
/// its closed region, by model-wide id (the input order), and that the model has
/// `input_triangles` triangles.
/// @throw as load_input_piece for an unreadable input.
void audit_binning(const TetMesh& mesh, std::span<const std::uint32_t> tets, const StoredIds& stored,
                   std::uint64_t input_triangles, std::span<const InputPiece> model,
                   AuditFindings& findings, Progress& progress = Progress::silent());

/// The same, and with CoordinateCheck::exact every stored corner equals the model's corner of
/// the triangle with that id: a problem names the shard, tet, triangle, corner and axis.
void audit_binning(const TetMesh& mesh, std::span<const std::uint32_t> tets,
                   const StoredTriangles& stored, CoordinateCheck coordinates,
                   std::uint64_t input_triangles, std::span<const InputPiece> model,
                   AuditFindings& findings, Progress& progress = Progress::silent());

/// The same for an index's tets and shards, comparing coordinates unless the index stores
/// them rounded (precision "float").
void audit_binning(const IndexReader& index, std::span<const InputPiece> model,
                   std::span<const std::uint32_t> tets, AuditFindings& findings,
                   Progress& progress = Progress::silent());

/// `boxes` random boxes inside the shard's bounds (sides from a hundredth to half of its
/// extent): the shard's query visits exactly the stored triangles that meet each box.
/// `label` names the shard in problems.
void audit_shard_queries(const Shard& shard, const std::string& label, std::uint32_t boxes,
                         std::uint64_t seed, AuditFindings& findings);

/// For each shard in `shards`, `boxes` random boxes inside the shard's bounds (sides from a
/// hundredth to half of its extent): the shard's query visits exactly the stored triangles
/// that meet the box.
void audit_shard_queries(const IndexReader& index, std::span<const std::uint32_t> shards,
                         std::uint32_t boxes, std::uint64_t seed, AuditFindings& findings,
                         Progress& progress = Progress::silent());

}  // namespace tetrapage
