#pragma once
/// @file Preprocess.h
/// The preprocess pipeline (DESIGN.md): ingest the parts, sample sites where the triangles
/// are, build the coarse Delaunay mesh, bin every triangle into the tets it meets (exactly),
/// build a grid or R-tree shard per non-empty tet, and write one HDF5 index under a temporary
/// name, renamed only when complete.
///
/// Memory: the ingest holds a few part files at a time plus a bounded sample of centroids; the
/// stages after sampling stream over spill files in blocks and process the tets in buckets
/// sized from --memory, so the working memory follows the budget, not the model.

#include <filesystem>
#include <string>
#include <vector>

#include "tetrapage/preprocess/PreprocessOptions.h"
#include "tetrapage/preprocess/PreprocessSummary.h"

namespace tetrapage {

/// The line of the index's `source` attribute that records `input` of an index written to
/// `index`: its path from the index's folder, a tab, its absolute path (so that the index finds
/// its model when both move together, and from any working directory).
std::string source_line(const std::filesystem::path& input, const std::filesystem::path& index);

/// Runs the pipeline over mesh files and manifests (.json) into `output`.
/// @throw IoError, FormatError, InputError (from the readers, naming the file), InputError for
///        an empty model or bad options; nothing is left at `output` on failure.
PreprocessSummary preprocess(const std::vector<std::filesystem::path>& inputs,
                             const std::filesystem::path& output,
                             const PreprocessOptions& options);

}  // namespace tetrapage
