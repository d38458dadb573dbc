#pragma once
/// @file WriteIndex.h
/// Stage 7 of the preprocess (docs/ARCHITECTURE.md): the mesh and the tables written, then
/// the header, and the temporary file renamed when complete.

#include <chrono>
#include <string>

#include "Ingest.h"
#include "Interiors.h"
#include "Shards.h"
#include "tetrapage/formats/index/IndexWriter.h"
#include "tetrapage/formats/index/TetMesh.h"
#include "tetrapage/preprocess/PreprocessOptions.h"
#include "tetrapage/preprocess/PreprocessSummary.h"

namespace tetrapage {

/// `source`: the inputs' source lines (source_line), one a line. The header's build report
/// is the summary so far, its seconds counted from `start`; summary.bytes_written is set.
void write_index(IndexWriter& writer, const TetMesh& mesh, const ShardTables& shards,
                 const IngestedModel& model, const Interiors& interiors, const std::string& source,
                 std::chrono::steady_clock::time_point start, PreprocessSummary& summary);

}  // namespace tetrapage
