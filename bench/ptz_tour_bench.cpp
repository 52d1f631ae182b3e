// What certifying a moving centre's occlusion along PTZ tour moves costs against sampling it, on
// the same points in the same run (docs/ptz.md): for each enabled PTZ camera of a rig with a tour
// and a centre offset, PtzTourWatch with the scene's triangles (PtzMoveClearWindows, exact) and
// without (every SampleStep, bisected), over points drawn uniformly in the study region's box
// (outside solids not tested: what the tours watch, not the fields). Prints both times, their
// ratio, and how the answers differ.
//
//   ptz_tour_bench SCENE.json RIG [POINTS=3000]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "analysis/geometry/ray_caster.h"
#include "analysis/geometry/surface_distance.h"
#include "analysis/geometry/visibility.h"
#include "analysis/scene/ptz.h"
#include "analysis/scene/scene.h"
#include "volume/ptz_fields.h"

using namespace pandora;

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: ptz_tour_bench SCENE.json RIG [POINTS]\n");
    return 2;
  }
  const Scene scene = LoadScene(argv[1]);
  const Rig& rig = scene.FindRig(argv[2]);
  const int n = argc > 3 ? std::atoi(argv[3]) : 3000;
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const auto t_build = std::chrono::steady_clock::now();
  const std::unique_ptr<SurfaceDistance> surfaces = PtzSweptOccluders(scene, rig);
  const double build_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t_build).count();
  if (!surfaces) {
    std::printf("no PTZ camera with a tour and an offset in rig %s\n", argv[2]);
    return 0;
  }
  const double scale = scene.ContentBounds().diagonal();
  const VisibilityTester exact(rig.cameras, *caster, scale, surfaces.get());
  const VisibilityTester sampled(rig.cameras, *caster, scale);
  std::mt19937_64 rng(1);
  const Aabb& box = scene.study.region.box;
  std::vector<Vec3> points;
  for (int i = 0; i < n; ++i) {
    Vec3 p;
    for (int a = 0; a < 3; ++a)
      p[a] = std::uniform_real_distribution<double>(box.min[a], box.max[a])(rng);
    points.push_back(p);
  }
  const double px = scene.study.ptz.min_px_per_m;
  std::printf("%s rig %s: %d points, %zu triangles (hierarchy built in %.3f s, %.1f MiB)\n",
              argv[1], argv[2], n, surfaces->triangle_count(), build_s,
              surfaces->bytes() / 1048576.0);
  for (int c = 0; c < static_cast<int>(rig.cameras.size()); ++c) {
    const Camera& cam = rig.cameras[c];
    if (!cam.enabled || !cam.ptz || cam.ptz->offset.isZero(0.0) || cam.ptz->tour.size() < 2)
      continue;
    const std::vector<PtzHead::TourLeg> legs = cam.ptz->TourLegs();
    const double period = legs.back().end();
    auto run = [&](const VisibilityTester& tester, std::vector<double>* watched) {
      const auto t0 = std::chrono::steady_clock::now();
      for (const Vec3& X : points)
        watched->push_back(PtzTourWatch(tester, c, legs, X, px).watched_s() / period);
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    };
    std::vector<double> we, ws;
    // Best of three each, interleaved.
    double te = 1e300, ts = 1e300;
    for (int k = 0; k < 3; ++k) {
      we.clear();
      ws.clear();
      ts = std::min(ts, run(sampled, &ws));
      te = std::min(te, run(exact, &we));
    }
    double mean_e = 0, mean_s = 0, max_diff = 0;
    int some_e = 0, some_s = 0, differ = 0;
    for (int i = 0; i < n; ++i) {
      mean_e += we[i] / n;
      mean_s += ws[i] / n;
      some_e += we[i] > 0;
      some_s += ws[i] > 0;
      const double d = std::abs(we[i] - ws[i]) * period;
      max_diff = std::max(max_diff, d);
      differ += d > 2e-3;
    }
    // Where the two differ, a brute-force loop over the period every 0.2 ms decides.
    const double dt = 2e-4;
    double worst_e = 0, worst_s = 0;
    for (int i = 0; i < n; ++i) {
      if (!(std::abs(we[i] - ws[i]) * period > 2e-3)) continue;
      double brute = 0;
      for (double t = 0.5 * dt; t < period; t += dt) {
        Ray r;
        if (!PtzSees(cam, *cam.ptz, cam.ptz->TourState(legs, t), points[i], px, nullptr, &r))
          continue;
        if (!PtzSegmentOccluded(exact, c, r, nullptr)) brute += dt;
      }
      worst_e = std::max(worst_e, std::abs(we[i] * period - brute));
      worst_s = std::max(worst_s, std::abs(ws[i] * period - brute));
    }
    std::printf("%s (offset %.3f m, period %.1f s): sampled %.3f s, certified %.3f s, ratio %.2f\n",
                cam.id.c_str(), cam.ptz->offset.norm(), period, ts, te, te / ts);
    std::printf(
        "  watched mean %.4f %% -> %.4f %%, at some time %.2f %% -> %.2f %%; %d points differ by "
        "more than 2 ms "
        "(largest %.3f s)\n",
        100 * mean_s, 100 * mean_e, 100.0 * some_s / n, 100.0 * some_e / n, differ, max_diff);
    std::printf(
        "  there, against a loop every %.1f ms: sampled off by up to %.4f s, certified by up to "
        "%.4f s\n",
        1e3 * dt, worst_s, worst_e);
  }
  return 0;
}
