// glTF/GLB and every other format Assimp imports: Assimp (in the CAD module) imports the scene
// in a child process, and its nodes become the soup's parts here.

#include <vector>

#include "CadIsolation.h"
#include "CadModule.h"
#include "ReaderSupport.h"
#include "tetrapage/formats/mesh/FileChecks.h"

namespace tetrapage::detail {
namespace {

// Assimp's reads are of files a person handles: minutes at most.
constexpr double kAssimpSeconds = 600;

}  // namespace

TriangleSoup read_assimp(const std::filesystem::path& path, ReadReport& report) {
  {
    // Our own open first: a missing or unreadable file is an IoError with the system's reason,
    // which Assimp's message would not tell apart from a malformed file.
    InputFile probe(path, 4096);
    report.bytes = probe.size();
  }
  // A glTF's buffers are opened by Assimp: a FIFO among them would block it forever.
  for (const auto& file : files_read_from(path)) require_regular_file(file);
  // Loaded here, before fork(), never in the child.
  const CadModule& module = cad_module(path);
  const CadContent content =
      read_in_child(path.string(), IsolationLimits{0, kAssimpSeconds, "Assimp"}, [&] { return module.import_scene(path); });
  SoupBuilder soup(path.string(), report);
  std::vector<std::uint32_t> corners(3);
  for (const TessellatedShape& part : content.shapes) {
    soup.begin_part(part.name);
    const auto base = static_cast<std::uint32_t>(soup.vertex_count());
    for (const Vec3& p : part.vertices) soup.add_vertex(p);
    for (const TriangleIndices& t : part.triangles) {
      for (int k = 0; k < 3; ++k) corners[k] = base + t[k];
      soup.add_polygon(corners);
    }
  }
  return soup.finish();
}

}  // namespace tetrapage::detail
