#pragma once
/// \file light.h
/// The light rule of the projective-light renderer (the Pandora paper's Fig. 2 and 4): how a
/// surface point's colour comes from the cameras that see it. One small pure function,
/// SurfaceLight, and its per-camera term, CameraLight; the CPU renderer (render.cpp) calls
/// CameraLight for every (point, camera) in camera order and adds the terms exactly as SurfaceLight
/// does, so the two agree bit for bit. A GLSL shader of a viewer implements the same formulas (see
/// docs/rendering.md, "The light rule") and is tested against SurfaceLight at the inputs of
/// render/light_test.cpp, within float round-off.
///
/// Header-only, no dependency but Eigen/Core: nothing here knows about rays, scenes or images. What
/// the rule needs from the geometry comes in as values (CameraAtPoint): whether the camera sees the
/// point (image bounds with distortion, working range, facing, and the shadow test: occlusion of
/// the segment to the camera), and for the grid pattern the point's pixel coordinates in the camera
/// and how fast they change per output pixel.
///
/// The rule, for a surface point P and the cameras c = 0 .. n-1 of the rig:
///
///     light(P) = sum over cameras c that see P of  brightness * w_c * colour_c
///
///     w_c = 1                                             (Pattern::kUniform)
///     w_c = fill + (1 - fill) * (1 - (1 - L(u_c, g_u)) * (1 - L(v_c, g_v)))   (Pattern::kGrid)
///
/// where (u_c, v_c) are P's pixel coordinates in camera c (OpenCV: pixel centres at integers),
/// g_u = |grad u_c| and g_v = |grad v_c| are camera pixels per output pixel (the norms of the
/// screen-space derivatives, GLSL's length(vec2(dFdx(u), dFdy(u)))), and L is the coverage of the
/// grid line family "a line every N camera pixels on the pixel borders u = kN - 1/2", drawn
/// line_width output pixels wide and box-filtered (GridLineCoverage). Overlaps add: k cameras on
/// one point give the sum of k lights (in linear RGB, unclamped). A camera that does not see P
/// (outside its image, out of range, facing away, or in shadow) adds nothing. Cameras are summed in
/// rig order, starting from zero, in double precision.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace pandora {

/// What each camera projects.
enum class Pattern {
  kUniform,  ///< Uniform light of the camera's colour over its whole footprint.
  kGrid,     ///< The camera's pixel grid: a line every `grid_pixels` of its pixels (Fig. 2 right).
};

/// Pattern's names in its order ("uniform", "grid"): `render --pattern`, a script's "light", the
/// viewer's panel.
inline const std::vector<std::string>& PatternNames() {
  static const std::vector<std::string> kNames{"uniform", "grid"};
  return kNames;
}
inline const std::string& PatternName(Pattern pattern) {
  return PatternNames()[static_cast<std::size_t>(pattern)];
}
/// The pattern PatternName calls `name`; nullopt for any other text.
inline std::optional<Pattern> PatternFromName(const std::string& name) {
  for (std::size_t i = 0; i < PatternNames().size(); ++i)
    if (PatternNames()[i] == name) return static_cast<Pattern>(i);
  return std::nullopt;
}

/// The default light scale for `enabled_cameras` cameras: min(1, 3 / n). Where k cameras overlap
/// their colours add, so with n cameras around a region the middle gets about n times one light;
/// scaling by 3 / n keeps the sum near white there while a spot lit by one camera keeps a third of
/// full light or more up to 9 cameras (docs/rendering.md, "Brightness", with measurements).
inline double DefaultBrightness(int enabled_cameras) {
  return enabled_cameras <= 3 ? 1.0 : 3.0 / enabled_cameras;
}

/// The parameters of the rule for one frame (RenderOptions resolved: brightness is a number).
struct LightRule {
  Pattern pattern = Pattern::kUniform;
  double brightness = 1.0;  ///< Multiplies every camera's light.
  int grid_pixels = 32;     ///< kGrid: a line every this many camera pixels (below 1 counts as 1).
  double grid_fill = 0.15;  ///< kGrid: light between the lines, as a fraction of the lines'.
  double line_width_px = 1.2;  ///< kGrid: line width in output pixels.
};

/// One camera at one surface point: the inputs of its term of the rule.
struct CameraAtPoint {
  /// The camera sees the point: inside its (distorted) image, within its range, facing it, and not
  /// in shadow (the segment to its centre is unoccluded). False: the camera adds nothing.
  bool sees = false;
  Eigen::Vector3d color = Eigen::Vector3d::Zero();  ///< The camera's light, linear RGB.
  /// kGrid only: the point projects into the camera (its pixel coordinates u, v are defined). When
  /// false the camera adds its fill light only.
  bool projects = false;
  /// kGrid: pixel coordinates of the point in the camera (pixel centres at integers).
  double u = 0, v = 0;
  double du = 0, dv = 0;  ///< kGrid: |grad u|, |grad v|: camera pixels per output pixel (>= 0).
};

/// Box-filtered coverage of a line `width` output pixels wide whose centre lies `distance` output
/// pixels from the pixel centre: clamp(width / 2 + 1/2 - distance, 0, 1).
inline double LineCoverage(double distance, double width) {
  return std::clamp(0.5 * width + 0.5 - distance, 0.0, 1.0);
}

/// Coverage of one family of grid lines (the camera pixel borders u = k n - 1/2, k integer) at
/// camera coordinate `u`, where `g` camera pixels pass per output pixel, lines `width` output
/// pixels wide. With s = n / g the line spacing in output pixels and d = |u - nearest line| / g:
///   L = (1 - f) * LineCoverage(d, width) + f * min(1, width / s),  f = clamp((3 - s) / 1.5, 0, 1),
/// i.e. lines closer than 3 output pixels fade into their mean coverage instead of aliasing.
/// 0 when g is 0, negative, infinite or NaN.
inline double GridLineCoverage(double u, double g, int n, double width) {
  const double f = (u + 0.5) / n;
  const double du = std::abs(f - std::round(f)) * n;  // camera pixels to the nearest line
  if (!(g > 0) || !std::isfinite(g)) return 0.0;
  const double spacing = n / g;  // output pixels between lines
  const double line = LineCoverage(du / g, width);
  const double mean = std::min(1.0, width / spacing);
  const double fade = std::clamp((3.0 - spacing) / 1.5, 0.0, 1.0);
  return (1.0 - fade) * line + fade * mean;
}

/// The weight w of a camera that sees the point: 1 for kUniform; for kGrid
/// fill + (1 - fill) * (1 - (1 - L_u) (1 - L_v)) with L from GridLineCoverage (0 when the point
/// does not project). 0 when the camera does not see the point.
inline double CameraLightWeight(const LightRule& rule, const CameraAtPoint& camera) {
  if (!camera.sees) return 0.0;
  if (rule.pattern != Pattern::kGrid) return 1.0;
  const int n = std::max(1, rule.grid_pixels);
  const double lu =
      camera.projects ? GridLineCoverage(camera.u, camera.du, n, rule.line_width_px) : 0.0;
  const double lv =
      camera.projects ? GridLineCoverage(camera.v, camera.dv, n, rule.line_width_px) : 0.0;
  const double line = 1.0 - (1.0 - lu) * (1.0 - lv);
  return rule.grid_fill + (1.0 - rule.grid_fill) * line;
}

/// One camera's term: (brightness * w) * colour, zero when it does not see the point.
inline Eigen::Vector3d CameraLight(const LightRule& rule, const CameraAtPoint& camera) {
  if (!camera.sees) return Eigen::Vector3d::Zero();
  return (rule.brightness * CameraLightWeight(rule, camera)) * camera.color;
}

/// THE light rule: the light that reaches a surface point from `count` cameras (rig order),
/// linear RGB, unclamped: the sum of CameraLight over the cameras, added in order from zero.
inline Eigen::Vector3d SurfaceLight(const LightRule& rule, const CameraAtPoint* cameras,
                                    std::size_t count) {
  Eigen::Vector3d light = Eigen::Vector3d::Zero();
  for (std::size_t c = 0; c < count; ++c)
    if (cameras[c].sees) light += CameraLight(rule, cameras[c]);
  return light;
}

/// The colour of a Surface::kMaterial point: albedo * light (per channel) plus a dim ambient term
/// shaded by the angle to the eye, ambient * (0.4 + 0.6 |cos_eye|) * albedo, where cos_eye is the
/// cosine between the surface normal and the eye ray. Other surface modes show the light itself.
inline Eigen::Vector3d MaterialColor(const Eigen::Vector3d& albedo, const Eigen::Vector3d& light,
                                     double ambient, double cos_eye) {
  const double shade = 0.4 + 0.6 * std::abs(cos_eye);
  return albedo.cwiseProduct(light) + ambient * shade * albedo;
}

}  // namespace pandora
