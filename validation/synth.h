#pragma once
/// \file synth.h
/// Synthetic captures of a design (`pandora synth`, `pandora validate`): what each camera of a rig
/// would record, through its exact lens model (distortion, fisheye, principal point), with plain
/// shading of the scene's materials, textures and printed fiducials and no projected light; then
/// exposure, optical blur and sensor noise; and the ground truth of every fiducial corner: its
/// world point and its exact pixel in each camera that images it.
///
/// Rendering is the exact CPU renderer's camera's-eye view (render/render.h) at the camera's native
/// size with every camera dark: colour = albedo x texture x (0.4 + 0.6 |cos|) (render/light.h's
/// MaterialColor with ambient 1), stratified samples^2 rays per pixel (the box filter of a sensor
/// pixel), pixel centres at integer coordinates as Camera::Project. Light header (no OpenCV).

#include <cstdint>
#include <string>
#include <vector>

#include "analysis/geometry/ray_caster.h"
#include "analysis/scene/scene.h"
#include "render/render.h"

namespace pandora {

class PreparedScene;

/// How the images are taken.
struct SynthOptions {
  int samples = 4;        ///< Rays per pixel per axis, 1..16 (the pixel's box filter).
  double exposure = 1.0;  ///< Multiplies the linear image before encoding, > 0.
  double blur_px = 0.0;   ///< Gaussian optical blur (sigma, pixels), >= 0, applied in linear light.
  double noise = 0.0;     ///< Gaussian noise (sigma, 8-bit grey levels), >= 0, after encoding.
  std::uint64_t seed = 1;  ///< Of the noise.
  /// Throws InputError naming the option ("--samples", "--exposure", "--blur", "--noise").
  void Check() const;
};

/// One camera's synthetic image (or the window of it that was rendered).
struct SynthImage {
  int camera = -1;  ///< Rig index.
  int width = 0, height = 0;
  RenderView::Window window;      ///< Where it lies in the camera's image (empty: the whole image).
  std::vector<std::uint8_t> rgb;  ///< 8-bit sRGB, 3 per pixel, row-major, y down.
  std::vector<std::uint8_t> grey;  ///< 8-bit, Rec. 601 luma of rgb (what detectors read).
  Image linear;  ///< The rendered linear image and its layers (depth: metres along the ray).
};

/// Renders rig camera `camera` (enabled or not) of `scene` (prepared over its caster) as it would
/// record it: the whole native image, or `window` of it. Every camera of `rig` stays dark.
SynthImage RenderSynth(const PreparedScene& prepared, const Rig& rig, int camera,
                       const SynthOptions& options, const RenderView::Window& window = {});

/// One camera's view of a fiducial corner.
struct CornerView {
  int camera = -1;            ///< Rig index.
  Vec2 pixel = Vec2::Zero();  ///< Camera::Project of the corner (distorted, OpenCV convention).
};

/// A fiducial corner in the scene and the cameras that image it.
struct CornerTruth {
  int fiducial = -1;  ///< Scene::fiducials index.
  int id = 0;         ///< FiducialCorners' id.
  Vec3 X = Vec3::Zero();
  /// The enabled cameras of the rig that image it: it projects inside the image, its printed face
  /// turns towards the camera (cos > 0) and nothing lies between (the segment from the camera's
  /// centre to the point, the point's own sheet excluded). Working ranges do not apply (they are
  /// a design's limits, not the optics').
  std::vector<CornerView> views;
};

/// Every corner of every fiducial of `scene` (at the time sample `scene` is at), with its views
/// in `rig`'s enabled cameras; `caster` over scene.AllTriangles().
std::vector<CornerTruth> FiducialCornerTruth(const Scene& scene, const Rig& rig,
                                             const RayCaster& caster);

}  // namespace pandora
