#pragma once
/// @file Interiors.h
/// Stage 3 of the preprocess (docs/ARCHITECTURE.md): each tet's reference point classified
/// against the closed components.

#include <cstdint>
#include <vector>

#include "Ingest.h"
#include "tetrapage/formats/index/TetMesh.h"
#include "tetrapage/preprocess/PreprocessOptions.h"
#include "tetrapage/preprocess/PreprocessSummary.h"

namespace tetrapage {

// The marker of an undecided tet in the interiors' component lists (so never a component id).
constexpr std::uint32_t kInteriorUndecided = 0xffffffffu;

// The interiors: each tet's reference point classified against the closed components, as CSR
// tables by tet (see docs/FORMAT.md), exactly, by vertical ray parity (RayParity.h) over one
// stream of the records per pass.
struct Interiors {
  std::vector<double> reference_points;   // 3 per tet; NaN for a tet without one
  std::vector<std::uint64_t> offsets;     // tet_count + 1
  std::vector<std::uint32_t> components;  // kInteriorUndecided marks an undecided tet
  bool stored = false;
};

/// Classifies every tet's reference point when options.interiors asks for it and some
/// component is closed (else `stored` stays false); counts the closed components in `summary`.
/// @throw InputError for an undecided tet, unless options.accept_undecided.
Interiors classify_interiors(IngestedModel& model, const TetMesh& mesh,
                             const PreprocessOptions& options, PreprocessSummary& summary);

}  // namespace tetrapage
