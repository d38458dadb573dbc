#include "tetrapage/tools/StudyEnvironment.h"

#include "tetrapage/tools/MeshLibrary.h"
#include "tetrapage/tools/SceneGenerator.h"
#include "tetrapage/tools/TerrainGenerator.h"
#include "tetrapage/tools/TetrasGenerator.h"

namespace tetrapage {

std::string to_string(EnvironmentKind kind) {
  switch (kind) {
    case EnvironmentKind::tetras: return "tetras";
    case EnvironmentKind::terrain: return "terrain";
    case EnvironmentKind::scene: return "scene";
  }
  return "?";
}

void generate_environment(EnvironmentKind kind, std::uint64_t triangles, std::uint64_t seed, MeshWriter& writer) {
  // Every generator's options start with the size and the seed.
  const auto sized = [&](auto options) {
    options.triangles = triangles;
    options.seed = seed;
    return options;
  };
  switch (kind) {
    case EnvironmentKind::tetras: generate_tetras(sized(TetrasOptions{}), writer); return;
    case EnvironmentKind::terrain: generate_terrain(sized(TerrainOptions{}), writer); return;
    case EnvironmentKind::scene: {
      static const MeshLibrary library = MeshLibrary::load_default();
      generate_scene(library, sized(SceneOptions{}), writer);
      return;
    }
  }
}

}  // namespace tetrapage
