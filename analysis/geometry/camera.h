#pragma once
/// \file camera.h
/// Camera model: intrinsics with OpenCV's distortion models and parameter names, and a posed
/// camera.
///
/// Frames (OpenCV): camera x right, y down, z forward. Pixel centres at integer coordinates; the
/// image covers [-0.5, width-0.5] x [-0.5, height-0.5]. World is right-handed, Z up, metres.
///
/// Lens models
///  - kPinhole:      u = fx*x + cx, v = fy*y + cy with (x, y) = (X/Z, Y/Z).
///  - kBrownConrady: OpenCV's `k1 k2 p1 p2 k3` (cv::projectPoints with 5 coefficients).
///  - kFisheye:      OpenCV's fisheye model `k1 k2 k3 k4` (cv::fisheye::projectPoints):
///                   theta = atan2(r, Z), theta_d = theta (1 + k1 theta^2 + k2 theta^4 + ...), and
///                   the distorted point is (theta_d / r) (X, Y) scaled by fx, fy. Because theta is
///                   computed with atan2, points behind the camera plane (Z <= 0) project when the
///                   field of view exceeds 180 degrees.
///
/// Valid domain. The radial map (r -> r_d for Brown-Conrady, theta -> theta_d for fisheye) is only
/// invertible where it is monotonic. `CameraModel` finds the first stationary point of the radial
/// map
/// (`max_radius()`, in normalized radius r for Brown-Conrady or in theta for fisheye); points
/// beyond it are not imaged by the real lens (the polynomial folds back) and `Project` returns
/// nullopt for them. For Brown-Conrady the 2x2 Jacobian of the full distortion (tangential terms
/// included) must also have a positive determinant.

#include <memory>
#include <optional>
#include <string>

#include "analysis/geometry/geometry.h"

namespace pandora {

enum class LensModel { kPinhole, kBrownConrady, kFisheye };

/// Returns "pinhole", "brown_conrady" or "fisheye".
const char* LensModelName(LensModel model);
/// The lens model LensModelName calls `name`; nullopt for any other text.
std::optional<LensModel> LensModelFromName(const std::string& name);
/// The distortion coefficients' names in Intrinsics' order: k1 k2 p1 p2 k3 k4.
extern const char* const kLensCoefficientNames[6];
/// Whether `model` uses coefficient `i` of kLensCoefficientNames (Brown-Conrady: k1 k2 p1 p2 k3;
/// fisheye: k1 k2 k3 k4; pinhole: none).
bool LensHasCoefficient(LensModel model, int i);

/// Intrinsic parameters. Units: pixels for focal lengths and principal point.
struct Intrinsics {
  int width = 0;
  int height = 0;
  double fx = 0, fy = 0;  ///< Focal lengths in pixels.
  double cx = 0, cy = 0;  ///< Principal point in pixels (pixel centres at integers).
  LensModel model = LensModel::kPinhole;
  /// Brown-Conrady uses k1 k2 p1 p2 k3; fisheye uses k1 k2 k3 k4; pinhole uses none.
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0, k4 = 0;
};

/// Focal length in pixels that gives a horizontal field of view `hfov_rad` across `width` pixels.
/// Pinhole and Brown-Conrady: fx = (width/2) / tan(hfov/2), hfov in (0, pi).
/// Fisheye (equidistant without distortion): fx = (width/2) / (hfov/2), hfov in (0, 2 pi).
/// The field of view is measured edge to edge of the image (width pixels), ignoring distortion.
double FocalFromHfov(double hfov_rad, int width, LensModel model);
/// Inverse of FocalFromHfov.
double HfovFromFocal(double fx, int width, LensModel model);
/// Focal length in pixels from the lens focal length and the sensor width, both in mm:
/// fx = focal_mm * width / sensor_width_mm.
double FocalFromLens(double focal_mm, double sensor_width_mm, int width);

/// An intrinsic camera model: projection and unprojection in the camera frame. Immutable value
/// type; construction precomputes the valid domain. Thread-safe for concurrent const use.
class CameraModel {
 public:
  CameraModel() = default;
  /// Does not validate ranges (the scene loader does); requires fx, fy > 0.
  explicit CameraModel(const Intrinsics& intrinsics);

  const Intrinsics& intrinsics() const { return k_; }
  int width() const { return k_.width; }
  int height() const { return k_.height; }

  /// Camera-frame point to distorted pixel. Returns nullopt when the point cannot be imaged: behind
  /// the camera (Z <= 0 for pinhole and Brown-Conrady; theta >= max_radius() for fisheye), beyond
  /// the monotonic domain, or on the optical centre. It does NOT check the image bounds (see
  /// InImage). If `d_pixel_d_point` is given it receives the 2x3 Jacobian d(u,v)/d(X,Y,Z) (pixels
  /// per metre).
  std::optional<Vec2> Project(const Vec3& p_camera, Mat23* d_pixel_d_point = nullptr) const;

  /// Distorted pixel to unit-length ray direction in the camera frame. Inverts the distortion with
  /// a safeguarded Newton iteration (bracketed in the monotonic domain, bisection fallback);
  /// returns nullopt when the pixel lies outside the image of the valid domain or the iteration
  /// fails. Round trip: Project(*Unproject(px)) == px to ~1e-9 px inside the domain.
  std::optional<Vec3> Unproject(const Vec2& pixel) const;

  /// True when the pixel lies in [-0.5, width-0.5] x [-0.5, height-0.5].
  bool InImage(const Vec2& pixel) const {
    return pixel.x() >= -0.5 && pixel.y() >= -0.5 && pixel.x() <= k_.width - 0.5 &&
           pixel.y() <= k_.height - 0.5;
  }

  /// Radius of the monotonic domain: normalized radius r = |(X/Z, Y/Z)| for Brown-Conrady (infinity
  /// when the radial polynomial never turns), theta in radians for fisheye (at most pi), infinity
  /// for pinhole.
  double max_radius() const { return max_radius_; }

  /// Largest angle (radians) between the optical axis and the ray through any pixel of the image
  /// (corners included, distortion included). Used for conservative culling. May exceed pi/2 for
  /// fisheye lenses. Computed from a dense sampling of the image border (refined at local extrema)
  /// and padded by 1e-6 relative; where part of the image lies beyond the image of the valid
  /// domain, the domain edge bounds it (atan(max_radius()) for Brown-Conrady, max_radius() for
  /// fisheye).
  double max_field_angle() const { return max_field_angle_; }

  /// Bounds of the normalized image-plane coordinates (x, y) = (X/Z, Y/Z) of all rays through the
  /// image, distortion included: [x_min, x_max] x [y_min, y_max], padded by 1e-6 relative (and
  /// widened to the domain's square [-r, r]^2 when part of the image lies beyond the domain). Only
  /// meaningful when max_field_angle() < pi/2; otherwise -inf, +inf, -inf, +inf.
  const Eigen::Vector4d& normalized_bounds() const { return normalized_bounds_; }

 private:
  Intrinsics k_;
  double max_radius_ = 0;
  double max_field_angle_ = 0;
  Eigen::Vector4d normalized_bounds_ = Eigen::Vector4d::Zero();  // x_min, x_max, y_min, y_max
};

/// A posed camera with its working range and display attributes.
struct PtzHead;

struct Camera {
  std::string id;       ///< Unique within its rig.
  std::string name;     ///< Human label (defaults to id).
  Vec3 color{1, 1, 1};  ///< Linear RGB in [0, 1], the colour of its light.
  bool enabled = true;
  Eigen::Isometry3d world_from_camera = Eigen::Isometry3d::Identity();
  CameraModel model;
  double near = 0.0;  ///< Working range, Euclidean distance from the centre, metres.
  double far = std::numeric_limits<double>::infinity();
  double pixel_sigma = 0.0;  ///< Pixel noise 1-sigma (pixels) for uncertainty; 0: the study's.
  /// A pan-tilt-zoom camera's head (analysis/scene/ptz.h); null for a fixed camera. The pose and
  /// intrinsics above are the head's current setting.
  std::shared_ptr<const PtzHead> ptz;

  Vec3 center() const { return world_from_camera.translation(); }
  Eigen::Isometry3d camera_from_world() const { return world_from_camera.inverse(); }

  /// World point to distorted pixel; nullopt as CameraModel::Project. With `d_pixel_d_world` the
  /// 2x3 Jacobian with respect to the world point (pixels per metre).
  std::optional<Vec2> Project(const Vec3& p_world, Mat23* d_pixel_d_world = nullptr) const;
};

/// Builds world_from_camera from a position, a point to look at and an up vector (world frame). The
/// camera's z axis points at `target`, its y axis (down in the image) is opposite `up` projected.
/// Returns nullopt when target == position or up is parallel to the viewing direction.
/// True when two cameras see alike: the same pose, lens (every intrinsic), working range, pixel
/// noise and enabled state, bit for bit; ids, names and colours aside. What decides whether fields
/// or images of a camera must be computed again.
bool SameCameraGeometry(const Camera& a, const Camera& b);

std::optional<Eigen::Isometry3d> LookAt(const Vec3& position, const Vec3& target, const Vec3& up);

}  // namespace pandora
