// The compiled part of the `tetrapage` package (python/tetrapage/__init__.py re-exports it).

#include "Bindings.h"
#include "tetrapage/formats/base/ByteSize.h"
#include "tetrapage/version.h"

PYBIND11_MODULE(_tetrapage, module) {
  using namespace tetrapage::python;
  module.doc() = "tetrapage: exact collision detection in huge CAD models, paged from disk.";
  module.attr("__version__") = TETRAPAGE_VERSION_STRING;
  // What memory=None means for Index and preprocess, as for every --memory.
  module.attr("DEFAULT_MEMORY") = tetrapage::kDefaultMemoryBudget;
  bind_errors(module);
  bind_meshes(module);
  bind_preprocess(module);
  bind_index(module);
  bind_objects(module);
  bind_groups(module);
  bind_obstacles(module);
}
