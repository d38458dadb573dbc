// The program around a ```cpp block of docs/USAGE.md marked <!-- fragment -->: the block runs
// in main() with `index` (a std::shared_ptr<const tetrapage::CollisionIndex> open on model.tpi)
// in scope and the runtime's headers included. UsageBlocks.cmake puts the block where the
// marker line below stands.
#include <cstdio>
#include <memory>
#include <vector>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/runtime/query/DynamicObstacles.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/runtime/query/ObjectGroup.h"

int main() {
  const auto index = std::make_shared<const tetrapage::CollisionIndex>("model.tpi");
  {
@USAGE_BLOCK@
  }
  return 0;
}
