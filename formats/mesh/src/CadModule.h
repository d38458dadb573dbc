#pragma once
// The CAD module: OpenCASCADE and Assimp, and the code that calls them, live in a shared
// module (tetrapage_cad.so) that formats loads the first time a file needs them. Why: linked
// into every program, their libraries' relocated data and static constructors made about
// 30 MiB of resident memory in every process, one that never reads a CAD file included (fly's
// peak under --memory at 100M). The caller checks, pre-scans and places; the module reads.

#include <filesystem>
#include <string>

#include "CadIsolation.h"
#include "tetrapage/formats/mesh/CadReader.h"

namespace tetrapage::detail {

/// Raised when the module's layout changes: a module of another build is refused.
inline constexpr unsigned kCadModuleVersion = 1;

/// What the module offers. Each function may throw tetrapage's errors.
struct CadModule {
  unsigned version = kCadModuleVersion;
  std::size_t options_size = sizeof(TessellationOptions);
  std::size_t content_size = sizeof(CadContent);
  /// A STEP or IGES file translated by OpenCASCADE and its shapes tessellated (on TBB's
  /// threads when `threads` is 0, else on as many threads of its own).
  CadContent (*read_occt_content)(const std::filesystem::path& path,
                                  const TessellationOptions& options, unsigned threads);
  /// A file Assimp imports: each node with meshes a shape of placed vertices, at its instance.
  CadContent (*import_scene)(const std::filesystem::path& path);
  /// Whether Assimp imports files of this extension (".3ds").
  bool (*assimp_imports)(const std::string& extension);
};

/// The module, loaded on the first call (thread-safe) from beside the program or library that
/// holds this code: the build tree's when that is in the build tree, else the installed one
/// ($TETRAPAGE_CAD_MODULE names another).
/// @throw IoError naming `file` (the file that needed it), the places looked in and why the
///        module could not be loaded.
const CadModule& cad_module(const std::filesystem::path& file);

/// Whether `path` has an IGES extension (.iges, .igs).
bool is_iges_path(const std::filesystem::path& path);

}  // namespace tetrapage::detail

/// The module's one exported symbol.
extern "C" const tetrapage::detail::CadModule* tetrapage_cad_module();
