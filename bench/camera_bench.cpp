// Micro-benchmarks of the per-point work of field evaluation (Google Benchmark). Not run by CI:
// `build/bench/camera_bench`. Whole-pipeline numbers against raw Embree come from `pandora bench`.
#include <benchmark/benchmark.h>

#include <random>

#include "analysis/geometry/camera.h"
#include "analysis/geometry/visibility.h"

namespace pandora {
namespace {

CameraModel MakeModel(LensModel model) {
  Intrinsics k;
  k.width = 1920;
  k.height = 1080;
  k.model = model;
  k.fx = k.fy = FocalFromHfov(model == LensModel::kFisheye ? 3.3 : 1.2, k.width, model);
  k.cx = 959.5;
  k.cy = 539.5;
  if (model == LensModel::kBrownConrady) k.k1 = -0.28, k.k2 = 0.07, k.p1 = 1e-4, k.p2 = -2e-4;
  if (model == LensModel::kFisheye) k.k1 = 0.05, k.k2 = -0.01, k.k3 = 0.002, k.k4 = -0.0003;
  return CameraModel(k);
}

std::vector<Vec3> Points() {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  std::vector<Vec3> p(4096);
  for (Vec3& x : p) x = Vec3(u(rng), u(rng), 1.0 + u(rng));
  return p;
}

void BM_Project(benchmark::State& state) {
  const CameraModel model = MakeModel(static_cast<LensModel>(state.range(0)));
  const bool jacobian = state.range(1) != 0;
  const std::vector<Vec3> points = Points();
  std::size_t i = 0;
  Mat23 J;
  for (auto _ : state) {
    benchmark::DoNotOptimize(model.Project(points[i++ & 4095], jacobian ? &J : nullptr));
  }
  state.SetLabel(std::string(LensModelName(model.intrinsics().model)) + (jacobian ? " +J" : ""));
}
BENCHMARK(BM_Project)->ArgsProduct({{0, 1, 2}, {0, 1}});

void BM_Unproject(benchmark::State& state) {
  const CameraModel model = MakeModel(static_cast<LensModel>(state.range(0)));
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Vec2> pixels(4096);
  for (Vec2& p : pixels) p = Vec2(1919 * u(rng), 1079 * u(rng));
  std::size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(model.Unproject(pixels[i++ & 4095]));
  state.SetLabel(LensModelName(model.intrinsics().model));
}
BENCHMARK(BM_Unproject)->Arg(0)->Arg(1)->Arg(2);

void BM_PixelDensity(benchmark::State& state) {
  const CameraModel model = MakeModel(LensModel::kBrownConrady);
  Mat23 J;
  model.Project(Vec3(0.1, 0.2, 1.0), &J);
  for (auto _ : state) {
    benchmark::DoNotOptimize(J);
    benchmark::DoNotOptimize(PixelDensity(J));
  }
}
BENCHMARK(BM_PixelDensity);

}  // namespace
}  // namespace pandora

BENCHMARK_MAIN();
