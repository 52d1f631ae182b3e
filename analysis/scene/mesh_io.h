#pragma once
/// \file mesh_io.h
/// Reading triangle meshes from files through assimp (OBJ+MTL, glTF/GLB, PLY, STL, COLLADA, FBX and
/// the other formats assimp reads). The only place that includes assimp.

#include <memory>
#include <string>
#include <vector>

#include "analysis/geometry/geometry.h"
#include "analysis/scene/skinning.h"

namespace pandora {

/// The triangles of a mesh file that share one material.
struct MeshPart {
  std::string material_name;  ///< The file's material name; "material<i>" when it has none.
  bool has_material = false;  ///< False when the file defines no material (assimp's default one).
  Vec3 color{0.7, 0.7, 0.7};  ///< Diffuse (base) colour of the material, RGB in [0, 1].
  /// Diffuse texture path resolved against the mesh file's folder; empty when none or embedded.
  std::string texture;
  /// Vertices in the file's own coordinates and units, node transforms applied; positions that are
  /// exactly equal are welded; counter-clockwise triangles as the file stores them.
  TriangleMesh mesh;
};

/// Reads the mesh file at `path`: triangulated, node transforms applied, points and lines dropped,
/// grouped into one part per material (parts in material order, empty materials left out).
/// COLLADA files are converted to Y up as assimp does (their declared up axis is honoured); other
/// formats keep their file coordinates.
/// Throws InputError (file `path`, empty JSON path) when the file is missing, empty or unreadable
/// (the reason carries assimp's message), holds non-finite coordinates, or has no triangles. Damage
/// that assimp 5.2 does not survive (it hangs, aborts or crashes) is caught before assimp reads the
/// file (PLY headers that promise more than the file holds, COLLADA index lists and accessors) or
/// before its post-processing runs (faces without vertices or with indices past the end), and
/// reported as "corrupt ...".
std::vector<MeshPart> LoadMeshFile(const std::string& path);

/// The user's memory budget for reading mesh files, while it lives (the innermost one counts): each
/// import may then hold at most `bytes` at once (besides its own cap from the file's size, which
/// guards against damaged files); past it the import ends in InputError naming the mesh file, the
/// budget and `where` ("{memory_budget_mb}", or "$.study.memory_budget_mb of scene.json"). The mesh
/// import's transient peak (assimp reading a 1M-triangle OBJ holds ~560 MiB) comes before any
/// triangle count is known, so this is the only check that can bound it. Not thread-safe: set by
/// a command around its scene loading.
class ScopedMeshImportBudget {
 public:
  ScopedMeshImportBudget(double bytes, std::string where);
  ~ScopedMeshImportBudget();
  ScopedMeshImportBudget(const ScopedMeshImportBudget&) = delete;
  ScopedMeshImportBudget& operator=(const ScopedMeshImportBudget&) = delete;
  /// Whether one is open.
  static bool active();

 private:
  double previous_bytes_;
  std::string previous_where_;
};

/// A mesh file read for skinned animation (analysis/scene/skinning.h).
struct SkinnedMeshFile {
  /// One part per material as LoadMeshFile groups them; each mesh in the rest pose (the node tree
  /// as the file places it, skinned), in the file's root frame; vertices welded only where both the
  /// position and the influences are equal.
  std::vector<MeshPart> parts;
  std::vector<std::shared_ptr<const SkinBinding>> bindings;  ///< Per part, vertex for vertex.
  std::shared_ptr<const Skeleton>
      skeleton;  ///< The node tree and every clip (key times in seconds).
};

/// Reads a mesh file with its node tree, bones and animations, without baking the node transforms
/// in: the same format list and damage checks as LoadMeshFile (bone weights naming vertices past
/// the end, negative or non-finite weights, non-finite keys and matrices are "corrupt ..."). Bone
/// weights are normalised to sum to 1; vertices without weight hang rigidly on their mesh's node
/// (so node-animated rigid meshes play too). Throws InputError (file `path`, empty JSON path) as
/// LoadMeshFile does, and when the file has no animation.
SkinnedMeshFile LoadSkinnedMeshFile(const std::string& path);

}  // namespace pandora
