#include "analysis/mesh_io.h"

#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cmath>
#include <filesystem>
#include <map>
#include <utility>

#include "analysis/error.h"
#include "analysis/primitives.h"

namespace pandora {
namespace {

namespace fs = std::filesystem;

// Reads the material's diffuse colour (glTF's base colour when there is no diffuse one).
bool MaterialColor(const aiMaterial& material, Vec3* color) {
  aiColor4D c;
  if (material.Get(AI_MATKEY_COLOR_DIFFUSE, c) != AI_SUCCESS &&
      material.Get(AI_MATKEY_BASE_COLOR, c) != AI_SUCCESS) {
    return false;
  }
  if (!std::isfinite(c.r) || !std::isfinite(c.g) || !std::isfinite(c.b)) return false;
  *color = Vec3(c.r, c.g, c.b).cwiseMax(0.0).cwiseMin(1.0);
  return true;
}

// Diffuse texture path resolved against `folder`; empty when none or embedded ("*0").
std::string MaterialTexture(const aiMaterial& material, const fs::path& folder) {
  aiString texture;
  if (material.GetTexture(aiTextureType_DIFFUSE, 0, &texture) != AI_SUCCESS &&
      material.GetTexture(aiTextureType_BASE_COLOR, 0, &texture) != AI_SUCCESS) {
    return {};
  }
  const std::string name = texture.C_Str();
  if (name.empty() || name[0] == '*') return {};
  const fs::path path(name);
  return path.is_absolute() ? path.string() : (folder / path).lexically_normal().string();
}

}  // namespace

std::vector<MeshPart> LoadMeshFile(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) {
    throw InputError(path, "", "mesh file not found",
                     "mesh paths are relative to the folder of the scene file");
  }
  if (fs::is_directory(path, ec)) throw InputError(path, "", "is a folder, not a mesh file");

  Assimp::Importer importer;
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                              aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* scene =
      importer.ReadFile(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                  aiProcess_PreTransformVertices | aiProcess_SortByPType);
  if (scene == nullptr) {
    std::string message = importer.GetErrorString();
    if (message.empty()) message = "unknown error";
    // What assimp says when removing points and lines (aiProcess_SortByPType) leaves nothing.
    if (message.find("No meshes remaining") != std::string::npos) {
      throw InputError(path, "", "mesh file has no triangles (only points or lines)",
                       "export the surfaces as polygons");
    }
    throw InputError(path, "", "cannot read mesh file: " + message,
                     "check that the file is a valid OBJ, glTF/GLB, PLY, STL, COLLADA or FBX file");
  }
  // A scene left without meshes (AI_SCENE_FLAGS_INCOMPLETE) is reported below as having no
  // triangles.
  const fs::path folder = fs::path(path).parent_path();
  // Material index -> part; std::map keeps the file's material order.
  std::map<unsigned, MeshPart> parts;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh& mesh = *scene->mMeshes[m];
    if (!(mesh.mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    MeshPart& part = parts[mesh.mMaterialIndex];
    TriangleMesh& out = part.mesh;
    const int offset = static_cast<int>(out.vertices.size());
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D& p = mesh.mVertices[v];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
        throw InputError(path, "", "cannot read mesh file: a vertex has non-finite coordinates");
      }
      out.vertices.emplace_back(p.x, p.y, p.z);
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;  // Points and lines, if any are left.
      out.triangles.emplace_back(offset + static_cast<int>(face.mIndices[0]),
                                 offset + static_cast<int>(face.mIndices[1]),
                                 offset + static_cast<int>(face.mIndices[2]));
    }
  }

  std::vector<MeshPart> result;
  for (auto& [material_index, part] : parts) {
    part.mesh = WeldVertices(part.mesh);
    if (part.mesh.triangles.empty()) continue;
    part.material_name = "material" + std::to_string(material_index);
    if (material_index < scene->mNumMaterials) {
      const aiMaterial& material = *scene->mMaterials[material_index];
      aiString name;
      if (material.Get(AI_MATKEY_NAME, name) == AI_SUCCESS && name.length > 0) {
        part.material_name = name.C_Str();
      }
      part.has_material = part.material_name != AI_DEFAULT_MATERIAL_NAME;
      if (part.has_material) {
        MaterialColor(material, &part.color);
        part.texture = MaterialTexture(material, folder);
      }
    }
    result.push_back(std::move(part));
  }
  if (result.empty()) {
    throw InputError(path, "", "mesh file has no triangles",
                     "points and lines are ignored; export the surfaces as polygons");
  }
  return result;
}

}  // namespace pandora
