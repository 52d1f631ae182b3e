#pragma once
/// \file visibility.h
/// Whether camera c sees point X: X projects inside c's image (distortion included, within the
/// lens's monotonic domain), lies within c's working range, faces c when it is a surface point, and
/// the segment from c's centre to X hits no triangle. Expected outcomes are values, never
/// exceptions.

#include <cstdint>
#include <vector>

#include "analysis/geometry/camera.h"
#include "analysis/geometry/ray_caster.h"

namespace pandora {

class SurfaceDistance;

/// Why a point is or is not seen, in the order the tests run (cheapest first).
enum class ViewResult : uint8_t {
  kSeen = 0,
  kDisabled,        ///< The camera is disabled.
  kOutOfRange,      ///< Distance from the centre outside [near, far].
  kNotProjectable,  ///< Behind the camera or beyond the lens's monotonic domain.
  kOutsideImage,    ///< Projects outside [-0.5, w-0.5] x [-0.5, h-0.5].
  kBackFacing,      ///< Surface point whose normal faces away from the camera.
  kOccluded,        ///< The segment to the camera hits geometry.
};

/// Returns a short lowercase name ("seen", "occluded", ...).
const char* ViewResultName(ViewResult result);

/// The local pixel density (pixels per metre) of a projection Jacobian: the geometric mean of the
/// two non-zero singular values of the 2x3 Jacobian d(pixel)/d(X), i.e. det(J J^T)^(1/4). For an
/// ideal pinhole on its axis this is f/Z. It measures displacements perpendicular to the viewing
/// ray, so lens distortion and obliquity count. Returns 0 for a degenerate Jacobian.
double PixelDensity(const Mat23& d_pixel_d_world);
/// PixelDensity of n Jacobians given as six arrays of their entries (J(0,0) J(0,1) J(0,2) J(1,0)
/// J(1,1) J(1,2)), rounded to float, into out[0..n): the same expressions in the same order, so
/// the same bits as static_cast<float>(PixelDensity(J)) (tested), 4 lanes wide where the CPU has
/// AVX2.
void PixelDensityLanes(int n, const double* const jac[6], float* out);

/// Per-camera visibility tests against one ray caster. Immutable; safe for concurrent const use.
class VisibilityTester {
 public:
  /// Relative epsilon for occlusion segments (times the scene scale); see epsilon().
  static constexpr double kRelativeEpsilon = 1e-5;
  /// Multiple of 2^-24 (float's unit round-off) in the per-ray float tolerance; see Tolerance().
  static constexpr double kFloatErrorFactor = 4.0;

  /// `scene_scale` is a length on the scale of the scene's geometry and region (the diagonal of
  /// Scene::ContentBounds(); not of Scene::Bounds(), which far cameras would inflate). The
  /// occlusion segment from a camera to X stops Tolerance() short of both ends, so a point lying on
  /// a surface is not occluded by that surface and single-precision round-off in the ray caster
  /// cannot flip the answer for occluders farther than that from the segment's ends
  /// (docs/accuracy.md). `surfaces` (optional, not owned) holds the caster's triangles in double
  /// precision: the tests that certify a whole family of segments at once (a PTZ head whose centre
  /// moves along a move, PtzSweptOcclusion) need it; nothing else reads it.
  VisibilityTester(const std::vector<Camera>& cameras, const RayCaster& caster, double scene_scale,
                   const SurfaceDistance* surfaces = nullptr);

  const std::vector<Camera>& cameras() const { return cameras_; }
  /// The floor of the tolerance: kRelativeEpsilon * scene_scale, metres.
  double epsilon() const { return epsilon_; }
  /// The tolerance of the occlusion segment from camera `camera` to a point `distance` metres away:
  /// max(epsilon(), kFloatErrorFactor * 2^-24 * (R + |C - O| + distance)), with O and R the centre
  /// and half-diagonal of the caster's bounds (Embree's float frame) and C the camera centre: the
  /// rounding of the ray's origin and direction and of the triangles' vertices in float.
  double Tolerance(int camera, double distance) const {
    const double f = float_error_base_[camera] + kFloatErrorFactor * 0x1p-24 * distance;
    return f > epsilon_ ? f : epsilon_;
  }

  /// Every test but occlusion. On kSeen, `segment` (if given) receives the occlusion segment from
  /// the camera centre to X, and `d_pixel_d_world` (if given) the 2x3 projection Jacobian at X.
  /// `normal` (world, any length) makes X a surface point that must face the camera.
  ViewResult TestGeometry(int camera, const Vec3& X, const Vec3* normal = nullptr,
                          Ray* segment = nullptr, Mat23* d_pixel_d_world = nullptr) const;

  /// TestGeometry with the Jacobian left in the camera frame: `d_pixel_d_camera` receives
  /// d(pixel)/d(camera-frame point); times camera_rotation(camera) it is d(pixel)/d(world). The
  /// field evaluation uses this to rotate only the Jacobians of segments that turn out unoccluded.
  /// Pixel density is rotation invariant: PixelDensity(d_pixel_d_camera) equals the world one.
  ViewResult TestGeometryCameraFrame(int camera, const Vec3& X, const Vec3* normal, Ray* segment,
                                     Mat23* d_pixel_d_camera) const;
  /// What TestGeometryBatch writes: the `count` points seen are points index[0..count) (ascending)
  /// of those tested; each quantity is in an array at the point's own position (not compacted):
  /// the occlusion segment (from `origin`, the camera centre) and the camera-frame Jacobian.
  struct GeometryBatch {
    int count = 0;
    Vec3 origin = Vec3::Zero();
    alignas(64) std::int16_t index[512];
    alignas(64) double dx[512], dy[512], dz[512], t_near[512], t_far[512];
    alignas(64) double jac[6][512];  ///< J(0,0) J(0,1) J(0,2) J(1,0) J(1,1) J(1,2)
    /// The segments of the points seen, for RayCaster::OccludedFan.
    RayCaster::Fan fan() const { return {origin, dx, dy, dz, t_near, t_far, index}; }
    /// The segment and the Jacobian of the k-th point seen.
    Ray segment(int k) const {
      const int i = index[k];
      Ray r;
      r.origin = origin;
      r.direction = Vec3(dx[i], dy[i], dz[i]);
      r.t_near = t_near[i];
      r.t_far = t_far[i];
      return r;
    }
    Mat23 jacobian(int k) const {
      const int i = index[k];
      Mat23 J;
      J << jac[0][i], jac[1][i], jac[2][i], jac[3][i], jac[4][i], jac[5][i];
      return J;
    }
  };
  /// TestGeometryCameraFrame without a normal for `n` points at once (world coordinates in three
  /// arrays, n <= 512) into `out`. The same arithmetic in the same order as the one-point test, so
  /// the same bits (tested), in a loop the compiler vectorises (4 doubles wide where the CPU has
  /// AVX2); fisheye lenses take the one-point test per point.
  void TestGeometryBatch(int camera, int n, const double* x, const double* y, const double* z,
                         GeometryBatch* out) const;
  /// R_camera_from_world of camera `camera`.
  const Mat3& camera_rotation(int camera) const { return rotation_[camera]; }
  /// The full test: TestGeometry, then the occlusion segment against the ray caster.
  ViewResult Test(int camera, const Vec3& X, const Vec3* normal = nullptr,
                  Mat23* d_pixel_d_world = nullptr) const;

  /// Test() for many points against one camera, in parallel. `results` is resized to points.size().
  void TestBatch(int camera, const std::vector<Vec3>& points,
                 std::vector<ViewResult>* results) const;

  const RayCaster& caster() const { return caster_; }
  /// The caster's triangles in double precision, or null (constructor).
  const SurfaceDistance* surfaces() const { return surfaces_; }

 private:
  std::vector<Camera> cameras_;
  std::vector<Eigen::Isometry3d> camera_from_world_;
  std::vector<Mat3> rotation_;  // camera_from_world_[c].linear()
  const RayCaster& caster_;
  const SurfaceDistance* surfaces_ = nullptr;
  double epsilon_;
  std::vector<double> float_error_base_;  // kFloatErrorFactor 2^-24 (R + |C - O|) per camera
};

}  // namespace pandora
