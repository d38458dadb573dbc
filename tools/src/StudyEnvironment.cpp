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
  switch (kind) {
    case EnvironmentKind::tetras: {
      TetrasOptions options;
      options.triangles = triangles;
      options.seed = seed;
      generate_tetras(options, writer);
      return;
    }
    case EnvironmentKind::terrain: {
      TerrainOptions options;
      options.triangles = triangles;
      options.seed = seed;
      generate_terrain(options, writer);
      return;
    }
    case EnvironmentKind::scene: {
      static const MeshLibrary library = MeshLibrary::load_default();
      SceneOptions options;
      options.triangles = triangles;
      options.seed = seed;
      generate_scene(library, options, writer);
      return;
    }
  }
}

}  // namespace tetrapage
