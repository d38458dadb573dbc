#pragma once
/// @file StudyEnvironment.h
/// The study's three environment groups behind one call (section 4.1): random-BSP tetras, fractal
/// terrains and scenes of real meshes, for the benchmarks and tests that sweep over all three.

#include <cstdint>
#include <string>

#include "tetrapage/formats/mesh/MeshWriter.h"

namespace tetrapage {

enum class EnvironmentKind : std::uint8_t { tetras, terrain, scene };

/// "tetras", "terrain" or "scene".
std::string to_string(EnvironmentKind kind);

/// Appends the environment of about `triangles` triangles to `writer` (the caller commits);
/// scenes use the default mesh library. Deterministic.
/// @throw InputError / IoError as the generators.
void generate_environment(EnvironmentKind kind, std::uint64_t triangles, std::uint64_t seed, MeshWriter& writer);

}  // namespace tetrapage
