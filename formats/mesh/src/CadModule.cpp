// Finding and loading the CAD module. Where it is looked for, in order:
//   $TETRAPAGE_CAD_MODULE, when set (a relocated installation);
//   the build tree's module, when the object holding this code (the program, libtetrapage.so,
//   the Python extension) lies in the build tree: a build never loads an installed module of
//   another build;
//   else beside that object as installed (LIBDIR/tetrapage/ seen from LIBDIR or from bin/),
//   then the configured install prefix's (a program linking the static library).

#include "CadModule.h"

#include <dlfcn.h>

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <sstream>
#include <cstdlib>
#include <string>
#include <vector>

#include "tetrapage/formats/base/Error.h"

namespace tetrapage::detail {
namespace {

namespace fs = std::filesystem;

constexpr const char* kModuleName = "tetrapage_cad.so";

// The file of the object (program or shared library) this code was linked into: the mapping
// that holds this function's code (dladdr names a program by its argv[0], not its path).
fs::path object_holding_this_code() {
  const auto address = reinterpret_cast<std::uintptr_t>(&object_holding_this_code);
  std::ifstream maps("/proc/self/maps");
  std::string line;
  while (std::getline(maps, line)) {
    std::istringstream fields(line);
    std::uintptr_t start = 0, end = 0;
    char dash = 0;
    std::string permissions, offset, device, inode, path;
    fields >> std::hex >> start >> dash >> end >> permissions >> offset >> device >> inode;
    std::getline(fields >> std::ws, path);
    if (address < start || address >= end || path.empty() || path.front() != '/') continue;
    std::error_code error;
    const fs::path object = fs::canonical(path, error);
    return error ? fs::path() : object;
  }
  return {};
}

bool lies_under(const fs::path& file, const fs::path& folder) {
  const auto [end, unused] = std::mismatch(folder.begin(), folder.end(), file.begin(), file.end());
  return end == folder.end();
}

std::vector<fs::path> module_candidates() {
  if (const char* named = std::getenv("TETRAPAGE_CAD_MODULE"); named != nullptr && *named != 0)
    return {fs::path(named)};
  const fs::path object = object_holding_this_code();
  std::error_code error;
  const fs::path build_tree = fs::weakly_canonical(TETRAPAGE_BUILD_DIR, error);
  if (!object.empty() && !error && lies_under(object, build_tree))
    return {fs::path(TETRAPAGE_CAD_MODULE_BUILT)};
  std::vector<fs::path> candidates;
  if (!object.empty()) {
    const fs::path folder = object.parent_path();
    candidates.push_back(folder / "tetrapage" / kModuleName);
    candidates.push_back(folder.parent_path() / TETRAPAGE_INSTALL_LIBDIR / "tetrapage" / kModuleName);
  }
  candidates.push_back(fs::path(TETRAPAGE_CAD_MODULE_INSTALLED));
  return candidates;
}

struct LoadedModule {
  const CadModule* module = nullptr;
  std::string failure;  // why each place failed, "; " between them

  void add_failure(const std::string& why) {
    if (!failure.empty()) failure.append("; ");
    failure.append(why);
  }
};

const CadModule* checked_table(void* handle, const fs::path& candidate, std::string& why) {
  using Entry = const CadModule* (*)();
  const auto entry = reinterpret_cast<Entry>(::dlsym(handle, "tetrapage_cad_module"));
  const CadModule* module = entry != nullptr ? entry() : nullptr;
  if (module == nullptr) {
    why = candidate.string() + " has no tetrapage_cad_module";
    return nullptr;
  }
  if (module->version != kCadModuleVersion || module->options_size != sizeof(TessellationOptions) ||
      module->content_size != sizeof(CadContent)) {
    why = candidate.string() + " belongs to another build of tetrapage";
    return nullptr;
  }
  return module;
}

LoadedModule load_module() {
  LoadedModule loaded;
  for (const fs::path& candidate : module_candidates()) {
    std::error_code error;
    if (!fs::is_regular_file(candidate, error)) {
      loaded.add_failure(candidate.string() + " not found");
      continue;
    }
    // Never closed: the soups and errors it made may outlive any caller's scope.
    void* handle = ::dlopen(candidate.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle == nullptr) {
      const char* reason = ::dlerror();
      loaded.add_failure(reason != nullptr ? reason : candidate.string() + " cannot be loaded");
      continue;
    }
    std::string why;
    loaded.module = checked_table(handle, candidate, why);
    if (loaded.module != nullptr) return loaded;
    loaded.add_failure(why);
  }
  return loaded;
}

}  // namespace

const CadModule& cad_module(const fs::path& file) {
  static const LoadedModule loaded = load_module();
  if (loaded.module == nullptr)
    throw IoError("'" + file.string() +
                  "': reading it needs tetrapage's CAD module (OpenCASCADE and Assimp), which "
                  "could not be loaded (" + loaded.failure +
                  "; TETRAPAGE_CAD_MODULE may name it)");
  return *loaded.module;
}

}  // namespace tetrapage::detail
