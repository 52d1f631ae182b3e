#pragma once
/// \file surface.h
/// The scene's surfaces as samples: points spread uniformly over every triangle at a target
/// spacing, each evaluated with the visibility rules for a surface point (it must face the camera)
/// and the same projection Jacobians and information matrix as the volume fields, and written as a
/// binary PLY point cloud (`pandora export-surface`, docs/report.md).

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "analysis/geometry/ray_caster.h"
#include "analysis/scene/scene.h"

namespace pandora {

/// One point on a surface of the scene.
struct SurfaceSample {
  Vec3 position = Vec3::Zero();  ///< World, metres.
  Vec3 normal = Vec3::UnitZ();  ///< Unit face normal (counter-clockwise winding seen from outside).
  int object = -1;              ///< Index into Scene::objects.
};

/// Sample counts above this are refused (about 1.6 GB of samples and values).
inline constexpr double kMaxSurfaceSamples = 2.0e7;

/// Which surfaces SampleSurfaces covers.
enum class SurfaceSelection {
  kAll,     ///< Every triangle of every object.
  kFacing,  ///< Triangles whose front faces the study region or an enabled camera (Faces).
};

/// True when some point of the study region, or one of `viewpoints`, lies strictly in front of the
/// plane of triangle (a, b, c) (counter-clockwise front): max of n . (X - a) > 0 with n the unit
/// normal, over the region box's 8 corners (a mesh region's vertices: the maximum of a linear
/// function over a polyhedron is at a vertex) and the viewpoints. A necessary condition for the
/// front to be visible from anywhere in the region or from those points; the outer faces of walls,
/// the floor's underside and the ceiling's top fail it when the cameras are inside the room.
/// Degenerate triangles: false.
bool FacesRegionOrViewpoints(const Region& region, const std::vector<Vec3>& viewpoints,
                             const Vec3& a, const Vec3& b, const Vec3& c);

/// Total triangle area of the scene's objects, m^2 (degenerate triangles count 0), of the selected
/// triangles (kFacing: facing the region or an enabled camera of `rig`; no rig: the region alone).
double SurfaceArea(const Scene& scene, SurfaceSelection selection = SurfaceSelection::kAll,
                   const Rig* rig = nullptr);

/// Samples the selected triangles uniformly by area: triangle t with area A_t gets
/// floor(A_t / spacing^2) points plus one more with probability frac(A_t / spacing^2), each point
/// uniform on the triangle, so the expected density is one point per spacing^2 everywhere.
/// Deterministic: the random numbers are a hash of (seed, object, triangle, sample), independent of
/// threads and platform, so a selection's samples are exactly the kAll samples on its triangles.
/// With kFacing and `rig`, no sample a camera of the rig sees is left out (a camera sees a surface
/// point only from in front of it). Throws InputError (file `option`, e.g. "{spacing}") when
/// spacing is not a positive finite number or the expected count exceeds kMaxSurfaceSamples.
std::vector<SurfaceSample> SampleSurfaces(const Scene& scene, double spacing,
                                          std::uint64_t seed = 1,
                                          const std::string& option = "{spacing}",
                                          SurfaceSelection selection = SurfaceSelection::kAll,
                                          const Rig* rig = nullptr);

/// The volume fields' quantities at one point (volume/fields.h defines each).
struct PointValues {
  int coverage = 0;                   ///< Cameras that see the point.
  std::vector<std::int32_t> cameras;  ///< The cameras (rig indices, ascending) that see it.
  double resolution = 0;      ///< px/m, best PixelDensity among those cameras; 0 when unseen.
  bool triangulable = false;  ///< >= 2 cameras and the information matrix observable.
  double sigma_max_mm = 0;    ///< Worst-direction static 1-sigma, mm; 0 when not triangulable.
  bool Sees(int camera) const { return std::binary_search(cameras.begin(), cameras.end(), camera); }
};

/// Evaluates points the way EvaluateFields evaluates voxel centres: for each camera in rig order
/// the visibility rules (VisibilityTester, with the surface normal when given, then the occlusion
/// segment), the projection Jacobian, J += A_c^T A_c / sigma_c^2 accumulated in the same order and
/// the same scalar form, and the eigenvalues of J (SymmetricEigenvalues3, as the fields) with the
/// same observability rule. At a voxel centre with no normal it gives the values stored in the
/// grids (surface_test checks every voxel). Immutable; safe for concurrent use.
class PointEvaluator {
 public:
  PointEvaluator(const Scene& scene, const Rig& rig, const RayCaster& caster);
  ~PointEvaluator();
  PointEvaluator(const PointEvaluator&) = delete;
  PointEvaluator& operator=(const PointEvaluator&) = delete;

  PointValues Evaluate(const Vec3& point, const Vec3* normal = nullptr) const;
  /// Evaluate() for every sample with its normal, in parallel.
  std::vector<PointValues> EvaluateSamples(const std::vector<SurfaceSample>& samples) const;

 private:
  struct Impl;
  Impl* impl_;
};

/// Writes the samples as a binary little-endian PLY point cloud, through a temporary file and a
/// rename. Vertex properties: float x y z (m), float nx ny nz, uchar red green blue (viridis of
/// coverage / enabled cameras; grey 128 where no camera sees the sample), float coverage (cameras),
/// float resolution (px/m, 0 where unseen), float sigma_max (mm, 0 where not triangulable), uchar
/// triangulable (1 or 0), int object (index into the scene's objects). `comments` become header
/// comment lines (one per entry, no newlines).
void WriteSurfacePly(const std::string& path, const std::vector<SurfaceSample>& samples,
                     const std::vector<PointValues>& values, int enabled_cameras,
                     const std::vector<std::string>& comments);

}  // namespace pandora
