#include "validation/synth.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "analysis/geometry/visibility.h"
#include "analysis/util/color.h"
#include "analysis/util/error.h"
#include "analysis/util/seeded.h"
#include "render/prepared_scene.h"

namespace pandora {

void SynthOptions::Check() const {
  if (samples < 1 || samples > 16) throw InputError("--samples", "", "must be 1 to 16");
  if (!(exposure > 0 && std::isfinite(exposure)))
    throw InputError("--exposure", "", "must be a positive number");
  if (!(blur_px >= 0 && blur_px <= 100)) throw InputError("--blur", "", "must be 0 to 100 px");
  if (!(noise >= 0 && noise <= 255)) throw InputError("--noise", "", "must be 0 to 255 levels");
}

SynthImage RenderSynth(const PreparedScene& prepared, const Rig& rig, int camera,
                       const SynthOptions& options, const RenderView::Window& window) {
  options.Check();
  Rig dark = rig;
  for (Camera& c : dark.cameras) c.enabled = false;
  const Camera& cam = rig.cameras[camera];
  RenderView view;
  view.camera = camera;
  view.width = cam.model.width();
  view.height = cam.model.height();
  view.window = window;
  RenderOptions ro;
  ro.surface = Surface::kMaterial;
  ro.ambient = 1.0;
  ro.brightness = 1.0;
  ro.samples = options.samples;
  ro.layers = false;
  ro.background = Vec3::Zero();
  ro.overlays.cameras = false;
  ro.overlays.key = false;
  ro.overlays.legend = false;
  SynthImage out;
  out.camera = camera;
  out.window = window;
  out.linear = Render(prepared, dark, view, ro);
  out.width = out.linear.width;
  out.height = out.linear.height;

  // Exposure and optical blur in linear light, then the sRGB curve and 8-bit noise.
  cv::Mat linear(out.height, out.width, CV_32FC3, out.linear.rgb.data());
  cv::Mat exposed = linear * options.exposure;
  if (options.blur_px > 0)
    cv::GaussianBlur(exposed, exposed, cv::Size(0, 0), options.blur_px, options.blur_px,
                     cv::BORDER_REPLICATE);
  const std::size_t pixels = static_cast<std::size_t>(out.width) * out.height;
  out.rgb.resize(3 * pixels);
  out.grey.resize(pixels);
  const float* src = exposed.ptr<float>();
  tbb::parallel_for(std::size_t(0), pixels, [&](std::size_t p) {
    // The noise of pixel p in the camera's whole image: the same wherever the window lies.
    const std::size_t x = p % out.width + std::max(0, window.x);
    const std::size_t y = p / out.width + std::max(0, window.y);
    const std::uint64_t key = y * 65536 + x;
    double luma = 0;
    for (int ch = 0; ch < 3; ++ch) {
      double v = 255.0 * SrgbFromLinear(std::clamp(double(src[3 * p + ch]), 0.0, 1.0));
      if (options.noise > 0) {  // Box-Muller from two seeded uniforms
        const double u1 = std::max(SeededUniform(options.seed, key, ch, 0), 1e-300);
        const double u2 = SeededUniform(options.seed, key, ch, 1);
        v += options.noise * std::sqrt(-2 * std::log(u1)) * std::cos(2 * 3.14159265358979 * u2);
      }
      const std::uint8_t q = static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
      out.rgb[3 * p + ch] = q;
      luma += (ch == 0 ? 0.299 : ch == 1 ? 0.587 : 0.114) * q;
    }
    out.grey[p] = static_cast<std::uint8_t>(std::clamp(std::lround(luma), 0L, 255L));
  });
  return out;
}

std::vector<CornerTruth> FiducialCornerTruth(const Scene& scene, const Rig& rig,
                                             const RayCaster& caster) {
  std::vector<CornerTruth> corners;
  for (int f = 0; f < static_cast<int>(scene.fiducials.size()); ++f) {
    const Fiducial& fid = scene.fiducials[f];
    for (const FiducialCorner& c : FiducialCorners(fid)) {
      CornerTruth t;
      t.fiducial = f;
      t.id = c.id;
      t.X = FiducialPoint(scene, fid, c.xy);
      corners.push_back(std::move(t));
    }
  }
  const VisibilityTester tester(rig.cameras, caster, scene.ContentBounds().diagonal());
  tbb::parallel_for(std::size_t(0), corners.size(), [&](std::size_t i) {
    CornerTruth& t = corners[i];
    const Vec3 normal = FiducialNormal(scene, scene.fiducials[t.fiducial]);
    for (int c = 0; c < static_cast<int>(rig.cameras.size()); ++c) {
      const Camera& cam = rig.cameras[c];
      if (!cam.enabled) continue;
      const Vec3 to_camera = cam.center() - t.X;
      const double distance = to_camera.norm();
      if (!(distance > 0) || !(normal.dot(to_camera) > 0)) continue;
      const std::optional<Vec2> pixel = cam.Project(t.X);
      if (!pixel || !cam.model.InImage(*pixel)) continue;
      // From the camera to just before the point, the fields' tolerance at both ends
      // (analysis/geometry/visibility.h): its own sheet is not in the way.
      const double tolerance = tester.Tolerance(c, distance);
      Ray ray;
      ray.origin = cam.center();
      ray.direction = -to_camera / distance;
      ray.t_near = tolerance;
      ray.t_far = distance - tolerance;
      if (caster.Occluded(ray)) continue;
      t.views.push_back({c, *pixel});
    }
  });
  return corners;
}

}  // namespace pandora
