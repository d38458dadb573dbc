// The CAD module's one exported symbol: the table of its functions.

#include "CadModule.h"

namespace tetrapage::detail {

CadContent read_occt_content(const std::filesystem::path& path, const TessellationOptions& options,
                             unsigned threads);
CadContent import_scene(const std::filesystem::path& path);
bool assimp_imports(const std::string& extension);

}  // namespace tetrapage::detail

extern "C" __attribute__((visibility("default"))) const tetrapage::detail::CadModule*
tetrapage_cad_module() {
  using namespace tetrapage::detail;
  static const CadModule module{kCadModuleVersion, sizeof(tetrapage::TessellationOptions),
                                sizeof(CadContent), &read_occt_content, &import_scene,
                                &assimp_imports};
  return &module;
}
