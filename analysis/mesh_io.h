#pragma once
/// \file mesh_io.h
/// Reading triangle meshes from files through assimp (OBJ+MTL, glTF/GLB, PLY, STL, COLLADA, FBX and
/// the other formats assimp reads). The only place that includes assimp.

#include <string>
#include <vector>

#include "analysis/geometry.h"

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

}  // namespace pandora
