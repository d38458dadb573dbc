// The Assimp half of glTF/GLB and every other format Assimp imports, in the CAD module. Assimp
// holds the whole scene in memory and, as Debian builds it (no ASSIMP_DOUBLE_PRECISION), in
// single precision: coordinates read this way are floats widened to double. The node
// transforms are composed in double.

#include <assimp/postprocess.h>
#include <fcntl.h>
#include <unistd.h>
#include <assimp/cimport.h>
#include <assimp/scene.h>

#include <array>
#include <assimp/Importer.hpp>
#include <map>
#include <set>
#include <vector>

#include "CadIsolation.h"
#include "CadModule.h"
#include "ReaderSupport.h"

namespace tetrapage::detail {
namespace {

using Matrix = std::array<double, 16>;  // row-major 4x4, as aiMatrix4x4

Matrix to_matrix(const aiMatrix4x4& m) {
  return {m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4,
          m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3, m.d4};
}

Matrix multiply(const Matrix& a, const Matrix& b) {
  Matrix product{};
  for (int row = 0; row < 4; ++row) {
    for (int column = 0; column < 4; ++column) {
      double sum = 0;
      for (int k = 0; k < 4; ++k) sum += a[4 * row + k] * b[4 * k + column];
      product[4 * row + column] = sum;
    }
  }
  return product;
}

Vec3 transform_point(const Matrix& m, const aiVector3D& p) {
  const double x = p.x, y = p.y, z = p.z;
  return {m[0] * x + m[1] * y + m[2] * z + m[3], m[4] * x + m[5] * y + m[6] * z + m[7],
          m[8] * x + m[9] * y + m[10] * z + m[11]};
}

struct MeshInstance {
  const aiNode* node;
  Matrix transform;
};

// Nodes deeper than this are taken for a hostile file (real scene graphs are a few dozen deep).
constexpr std::size_t kMaxNodeDepth = 1024;

// Every node with meshes and its transform, depth first, without recursion (a file may nest
// nodes deeply). An importer may leave null children (Assimp 5.2's RAW importer does).
void collect_instances(const std::string& file, const aiNode* root, const Matrix& identity,
                       std::vector<MeshInstance>& instances) {
  struct Pending {
    const aiNode* node;
    Matrix parent;
    std::size_t depth;
  };
  std::vector<Pending> pending{{root, identity, 0}};
  while (!pending.empty()) {
    const Pending next = pending.back();
    pending.pop_back();
    // Its meshes would be lost without a word: refuse the file instead.
    if (next.node == nullptr)
      throw FormatError(file + ": Assimp's scene has a missing node (a null child at depth " +
                        std::to_string(next.depth) + "): its meshes cannot be placed");
    if (next.depth > kMaxNodeDepth)
      throw FormatError(file + ": the scene's nodes nest deeper than " +
                        std::to_string(kMaxNodeDepth));
    const Matrix transform = multiply(next.parent, to_matrix(next.node->mTransformation));
    if (next.node->mNumMeshes > 0) instances.push_back({next.node, transform});
    if (next.node->mNumChildren > 0 && next.node->mChildren == nullptr)
      throw FormatError(file + ": Assimp's scene has a node with " +
                        std::to_string(next.node->mNumChildren) +
                        " children and no list of them: their meshes cannot be placed");
    // Reversed, so that children come out in the file's order.
    for (unsigned c = next.node->mNumChildren; c-- > 0;)
      pending.push_back({next.node->mChildren[c], transform, next.depth + 1});
  }
}

// Mesh `m` of `node`, placed by `transform`, appended to `part`: its vertices, and its faces of
// three or more corners (points and lines bound no surface) fanned into triangles.
void add_mesh(const std::filesystem::path& path, const aiScene* scene, const aiNode* node, unsigned m,
              const Matrix& transform, TessellatedShape& part) {
  // An importer's scene is input too: a mesh it names must exist and hold its arrays.
  if (node->mMeshes == nullptr || scene->mMeshes == nullptr || node->mMeshes[m] >= scene->mNumMeshes)
    throw FormatError(path.string() + ": node '" + node->mName.C_Str() + "' names a mesh the scene lacks");
  const aiMesh* mesh = scene->mMeshes[node->mMeshes[m]];
  if (mesh == nullptr || (mesh->mNumVertices > 0 && mesh->mVertices == nullptr) ||
      (mesh->mNumFaces > 0 && mesh->mFaces == nullptr))
    throw FormatError(path.string() + ": mesh " + std::to_string(node->mMeshes[m]) + " of node '" +
                      node->mName.C_Str() + "' has no vertex or face array");
  if (part.vertices.size() + mesh->mNumVertices > max_vertices)
    throw InputError(path.string() + ": more vertices than a soup can index");
  const auto base = static_cast<std::uint32_t>(part.vertices.size());
  const std::string where =
      path.string() + ": node '" + node->mName.C_Str() + "' mesh " + std::to_string(node->mMeshes[m]);
  for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
    const Vec3 p = transform_point(transform, mesh->mVertices[v]);
    if (!is_finite(p)) throw_not_finite(where + " vertex " + std::to_string(v) + ": ", p);
    part.vertices.push_back(p);
  }
  for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
    const aiFace& face = mesh->mFaces[f];
    if (face.mNumIndices < 3) continue;
    if (face.mIndices == nullptr) throw FormatError(where + " face " + std::to_string(f) + ": no vertex indices");
    for (unsigned k = 0; k < face.mNumIndices; ++k)
      if (face.mIndices[k] >= mesh->mNumVertices)
        throw InputError(where + " face " + std::to_string(f) + ": vertex index " + std::to_string(face.mIndices[k]) +
                         " out of range (" + std::to_string(mesh->mNumVertices) + " vertices)");
    for (unsigned k = 1; k + 1 < face.mNumIndices; ++k)
      part.triangles.push_back({base + face.mIndices[0], base + face.mIndices[k], base + face.mIndices[k + 1]});
  }
}

}  // namespace

// Assimp's import and the walk of its scene, in the child process: each node with meshes is a
// shape of placed vertices and triangles (polygons fanned from their first corner, as the soup
// would), named as its part. Assimp's crash on a crafted file (a read of freed memory in the
// glTF importer, found by fuzzing) then ends the child only.
CadContent import_scene(const std::filesystem::path& path) {
  // Runs in the child only. Assimp's failed assertions write to stderr before they abort: the
  // caller's one-line error names the crash instead.
  if (const int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC); null >= 0) {
    ::dup2(null, STDERR_FILENO);
    ::close(null);
  }
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path.string(), aiProcess_Triangulate);
  if (scene != nullptr && scene->mNumMeshes == 0) {
    // Assimp flags a scene without meshes as incomplete; to us it is a valid, empty file.
    throw InputError(path.string() + ": the mesh has no triangle (no mesh in the scene)");
  }
  if (scene == nullptr || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0 ||
      scene->mRootNode == nullptr) {
    const std::string reason = importer.GetErrorString();
    throw FormatError(path.string() + ": Assimp cannot import it: " +
                      (reason.empty() ? std::string("no reason given") : reason));
  }
  std::vector<MeshInstance> instances;
  const Matrix identity{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  collect_instances(path.string(), scene->mRootNode, identity, instances);
  const std::string stem = path.stem().string();
  CadContent content;
  std::set<std::string> used_names;
  std::map<std::string, std::uint64_t> next_suffix;
  std::uint64_t vertices = 0;
  for (std::size_t i = 0; i < instances.size(); ++i) {
    const aiNode* node = instances[i].node;
    std::string name = stem;
    if (instances.size() > 1) {
      const std::string node_name =
          node->mName.length > 0 ? std::string(node->mName.C_Str()) : "node" + std::to_string(i);
      name = stem + "/" + node_name;
    }
    // Instances of one node name (or unnamed nodes) still get distinct part names.
    if (!used_names.insert(name).second) {
      // Each name's next suffix is kept: n nodes of one name take linear time.
      std::uint64_t& k = next_suffix.try_emplace(name, 2).first->second;
      const std::string base_name = name + "#";
      while (!used_names.insert(base_name + std::to_string(k)).second) ++k;
      name = base_name + std::to_string(k++);
    }
    TessellatedShape part;
    part.name = name;
    for (unsigned m = 0; m < node->mNumMeshes; ++m) add_mesh(path, scene, node, m, instances[i].transform, part);
    vertices += part.vertices.size();
    if (vertices > max_vertices) throw InputError(path.string() + ": more vertices than a soup can index");
    content.instances.push_back({content.shapes.size(), {}, name});
    content.shapes.push_back(std::move(part));
  }
  return content;
}

bool assimp_imports(const std::string& extension) {
  return aiIsExtensionSupported(extension.c_str()) == AI_TRUE;
}

}  // namespace tetrapage::detail
