#pragma once
/// \file surface_targets.h
/// Targets on surfaces: points spread over named objects' surfaces (a body, a face, a prop), moving
/// with their object through the study's time samples, each tested against every enabled camera as
/// a surface point (in the image, in range, facing the camera, not occluded, by the scene at that
/// sample, the object itself included). What a mocap or reconstruction rig must see is the
/// markers and skin on moving bodies, not the empty volume around them. docs/time.md.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "analysis/scene/scene.h"

namespace pandora {

class RigidPartsRayCaster;

/// One target's points and, per time sample, how many cameras see each.
struct SurfaceTargetResult {
  std::string name;  ///< The group or object name given in the study.
  int points = 0;    ///< Points on its surface (area-uniform).
  int samples = 0;   ///< Time samples (1 for a static scene).
  /// share_ge[k - 1]: share of (point, sample) pairs seen by at least k cameras, k = 1 .. max(3,
  /// min_cameras).
  std::vector<double> share_ge;
  /// Per sample, the share of the points seen by at least min_cameras cameras.
  std::vector<double> sample_share;
  /// Share of the points seen by at least min_cameras cameras in every sample.
  double always = 0;
  int worst_sample = 0;  ///< Index of the sample with the lowest sample_share.
  /// Per camera of the rig (rig order; disabled cameras 0): share of the pairs it sees.
  std::vector<double> per_camera;
  /// cameras[sample * points + point]: how many cameras see the point at that sample (kept for
  /// tests and pictures).
  std::vector<std::uint16_t> cameras;
  /// Per pixel target of the study (Study::pixel_targets): share of the (point, sample) pairs seen
  /// by at least min_cameras cameras each at that target's pixel density or more.
  std::vector<double> pixel_share;
  double seconds = 0;  ///< Wall time of this target's points over all samples.
};

/// A target's surface as placed (the triangles of the objects SceneObject::InGroup(name) takes) and
/// the motion that moves them (index into Scene::motions, that of its first object; -1: none).
struct TargetSurface {
  TriangleMesh mesh;
  int motion = -1;
  std::vector<int> objects;  ///< The objects whose meshes `mesh` appends, in order.
  /// Some of them play a skinned animation: their points follow the skin (PlaceTargetPoints).
  bool skinned = false;
  /// Per object of `objects`: its first triangle in `mesh`, and its capsule when it is a part of
  /// a person (points inside another part are not on the body's surface: SampleTargetPoints
  /// skips them).
  std::vector<int> first_triangle;
  std::vector<std::optional<SceneObject::CapsuleAxis>> capsules;
};
TargetSurface FindTargetSurface(const Scene& scene, const std::string& name);

/// Points uniform by area on `mesh` (seeded, reproducible), with their triangles' unit normals;
/// when asked, each point's triangle and its barycentric weights of the triangle's 2nd and 3rd
/// corners.
void SampleSurface(const TriangleMesh& mesh, int count, std::uint64_t seed,
                   std::vector<Vec3>* points, std::vector<Vec3>* normals,
                   std::vector<int>* triangles = nullptr,
                   std::vector<Eigen::Vector2d>* barycentric = nullptr);

/// A target's points as placed (SampleSurface on TargetSurface::mesh).
struct SurfacePoints {
  std::vector<Vec3> points, normals;
  std::vector<int> triangles;
  std::vector<Eigen::Vector2d> barycentric;
};
SurfacePoints SampleTargetPoints(const TargetSurface& surface, int count, std::uint64_t seed);

/// The points and their unit normals at `sample`: moved rigidly by the surface's motion, or, on a
/// surface with skinned objects, at the same barycentric coordinates of their triangles in the
/// sample's pose (ObjectVerticesAt), the normal that of the posed triangle.
void PlaceTargetPoints(const Scene& scene, const TargetSurface& surface, const SurfacePoints& rest,
                       const TimeSample& sample, std::vector<Vec3>* points,
                       std::vector<Vec3>* normals);

/// Evaluates every target of scene.study.targets for the enabled cameras of `rig` at `samples`
/// (Scene::TimeSamples(); an empty list: the scene as placed, one sample). `parts` is
/// MakeSceneParts(scene). `min_cameras` is the k of sample_share and always.
std::vector<SurfaceTargetResult> EvaluateSurfaceTargets(const Scene& scene, const Rig& rig,
                                                        const RigidPartsRayCaster& parts,
                                                        const std::vector<TimeSample>& samples,
                                                        int min_cameras);

}  // namespace pandora
