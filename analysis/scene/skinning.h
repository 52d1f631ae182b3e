#pragma once
/// \file skinning.h
/// Skinned (boned) meshes: a node hierarchy with its animation clips, sampled from a mesh file by
/// assimp (analysis/scene/mesh_io.cpp, the only place that includes assimp) into these light
/// structs, and linear-blend skinning evaluated in double precision. A skinned object of a scene
/// plays one clip
/// ("animation" in the scene file, docs/scene-format.md "Skinned animation"); at a time sample its
/// vertices are the skinned pose at the clip's time, in the object's placement (docs/time.md).

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "analysis/geometry/geometry.h"

namespace pandora {

/// One node of a mesh file's node tree.
struct SkeletonNode {
  std::string name;
  int parent = -1;  ///< Index of the parent node (parents come before their children); -1: root.
  /// The node's own transform relative to its parent, as the file places it (unanimated).
  Eigen::Matrix4d rest_local = Eigen::Matrix4d::Identity();
};

/// Keys of one animated node: positions and scalings interpolate linearly, rotations by slerp
/// (shortest arc); before the first key the first holds, after the last the last. A kind without
/// keys keeps the node's rest value of it.
struct NodeChannel {
  int node = 0;
  std::vector<std::pair<double, Vec3>> position;  ///< (seconds, value), times increasing.
  std::vector<std::pair<double, Eigen::Quaterniond>> rotation;  ///< Unit quaternions.
  std::vector<std::pair<double, Vec3>> scaling;
};

/// One animation of the file.
struct SkinClip {
  std::string name;  ///< As the file names it; may be empty.
  double duration_s = 0;
  std::vector<NodeChannel> channels;
  /// Distinct key times (seconds) of all channels, sorted.
  std::vector<double> KeyTimes() const;
};

/// A file's node tree and clips, shared by the objects made from the file.
struct Skeleton {
  std::vector<SkeletonNode> nodes;
  std::vector<SkinClip> clips;

  /// Every node's transform to the file's root frame (its global transform) at `clip_time_s` of
  /// clips[clip]; clip -1: the rest pose (each node's rest_local). Nodes without keys keep their
  /// rest.
  std::vector<Eigen::Matrix4d> Globals(int clip, double clip_time_s) const;
  /// "'walk' (0), 'run' (1)" for messages; unnamed clips by index.
  std::string ClipList() const;
};

/// How the vertices of one mesh (a scene object) hang on the skeleton.
struct SkinBinding {
  /// A bone: a node and its offset matrix (the file's mesh space to the bone's space at bind time).
  /// Vertices the file gives no weight hang rigidly on their mesh's node (offset the identity).
  std::vector<std::pair<int, Eigen::Matrix4d>> bones;
  /// The file's vertex positions in mesh space, one per vertex of the object's mesh.
  std::vector<Vec3> mesh_vertices;
  /// Per vertex, its influences: (bone index, weight) in [first[v], first[v + 1]); the weights sum
  /// to 1 (normalised on load).
  std::vector<int> first;
  std::vector<std::pair<int, double>> influences;

  /// Vertices in the file's root frame for node transforms `globals` (Skeleton::Globals):
  /// sum over influences of weight * globals[node] * offset * mesh_vertex.
  std::vector<Vec3> Skin(const std::vector<Eigen::Matrix4d>& globals) const;
};

/// A scene object that plays a clip ("animation" in the scene file).
struct SkinnedObject {
  int object = -1;  ///< Index into Scene::objects.
  std::shared_ptr<const Skeleton> skeleton;
  std::shared_ptr<const SkinBinding> binding;
  int clip = 0;           ///< Index into skeleton->clips.
  double speed = 1.0;     ///< Clip seconds per scene second (> 0).
  double offset_s = 0.0;  ///< Clip time at scene time 0.
  bool loop = true;       ///< Wrap the clip time into [0, duration); else clamp to it.
  /// The object's placement: the file's root frame to world (unit scale, up axis, instance
  /// transform).
  Eigen::Affine3d world_from_file = Eigen::Affine3d::Identity();

  /// The clip time at scene time `t`: offset_s + speed * t, wrapped or clamped.
  double ClipTime(double t) const;
  /// The object's vertices (world, before any rigid motion of its group) at scene time `t`; empty
  /// when the scene was loaded without meshes (no skeleton).
  std::vector<Vec3> VerticesAt(double t) const;
  /// The object's vertices in the rest pose (the node tree as the file places it), world.
  std::vector<Vec3> RestVertices() const;
};

}  // namespace pandora
