// (f) The Monte Carlo gate per voxel (app/session/accuracy.h): at sampled voxels, the sample
// covariance of noisy Ceres triangulations against the predicted J^-1, eigenvalue by eigenvalue
// and axis by axis.
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "analysis/geometry/triangulation.h"
#include "analysis/geometry/visibility.h"
#include "analysis/util/seeded.h"
#include "analysis/util/text.h"
#include "app/session/accuracy.h"

namespace pandora {
namespace {

constexpr double kGateNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kGateDegPerRad = 180.0 / 3.14159265358979323846;

// Eigenvalues largest first and their eigenvectors as columns in the same order.
void SortedEigen(const Mat3& m, double values[3], Mat3* vectors) {
  const Eigen::SelfAdjointEigenSolver<Mat3> solver(m);
  for (int a = 0; a < 3; ++a) {
    values[a] = solver.eigenvalues()(2 - a);
    vectors->col(a) = solver.eigenvectors().col(2 - a);
  }
}

// The sample's statistical error of axis i's direction (degrees): the largest over the other axes
// of sqrt(l_i l_j / (n - 1)) / |l_i - l_j| (kGateResolvableDeg).
double AxisStandardErrorDeg(const double l[3], int i, int samples) {
  double worst = 0;
  for (int j = 0; j < 3; ++j) {
    if (j == i) continue;
    const double gap = std::abs(l[i] - l[j]);
    if (!(gap > 0)) return std::numeric_limits<double>::infinity();
    worst = std::max(worst, std::sqrt(l[i] * l[j] / (samples - 1)) / gap);
  }
  return worst * kGateDegPerRad;
}

// Sample skewness of the offsets along `axis` (about their mean).
double Skewness(const std::vector<Vec3>& offsets, const Vec3& axis) {
  const double n = static_cast<double>(offsets.size());
  if (n < 3) return kGateNaN;
  double mean = 0;
  for (const Vec3& d : offsets) mean += d.dot(axis);
  mean /= n;
  double m2 = 0, m3 = 0;
  for (const Vec3& d : offsets) {
    const double e = d.dot(axis) - mean;
    m2 += e * e;
    m3 += e * e * e;
  }
  m2 /= n;
  m3 /= n;
  return m2 > 0 ? m3 / std::pow(m2, 1.5) : kGateNaN;
}

// A candidate voxel centre: uniform over the region's voxels, from (seed, k).
Vec3 CandidateVoxel(const Aabb& box, double voxel, std::uint64_t seed, std::uint64_t k) {
  Vec3 p;
  for (int a = 0; a < 3; ++a) {
    const double extent = box.max[a] - box.min[a];
    const double count = std::max(1.0, std::floor(extent / voxel));
    const double index = std::min(count - 1, std::floor(SeededUniform(seed, k, a) * count));
    p[a] = box.min[a] + (index + 0.5) * std::min(voxel, extent);
  }
  return p;
}

}  // namespace

double GateStudy::PassShare() const {
  if (voxels.empty()) return kGateNaN;
  double passed = 0;
  for (const GateVoxel& v : voxels) passed += v.pass ? 1 : 0;
  return passed / static_cast<double>(voxels.size());
}

GateStudy RunGateStudy(const Scene& scene, const Rig& rig, const RayCaster& caster,
                       const AccuracyOptions& options) {
  options.Check();
  GateStudy study;
  study.trials = options.gate_trials;
  study.sigma_px = scene.study.pixel_sigma;
  const VisibilityTester tester(rig.cameras, caster, scene.Bounds().diagonal());
  const Aabb& box = scene.study.region.box;
  const std::uint64_t wanted = static_cast<std::uint64_t>(options.gate_voxels);
  std::vector<SamplePoint> points;
  std::uint64_t k = 0;
  for (; k < 200 * wanted && points.size() < wanted; ++k) {
    SamplePoint p;
    p.X = CandidateVoxel(box, scene.study.voxel_size, options.seed ^ 0x6a7eull, k);
    for (std::size_t c = 0; c < rig.cameras.size(); ++c)
      if (rig.cameras[c].enabled && tester.Test(static_cast<int>(c), p.X) == ViewResult::kSeen)
        p.cameras.push_back(rig.cameras[c]);
    if (p.cameras.size() < 2) continue;
    if (!(PredictUncertainty(p, study.sigma_px).triangulable)) continue;
    points.push_back(std::move(p));
  }
  if (points.size() < wanted)
    study.notes.push_back(Format(
        "%zu of %llu candidate voxels are seen by >= 2 cameras and "
        "triangulable; the gate has %zu voxels, not %d",
        points.size(), static_cast<unsigned long long>(k), points.size(), options.gate_voxels));
  const auto start = std::chrono::steady_clock::now();
  std::uint64_t seed = options.seed;
  for (const SamplePoint& p : points) {
    std::vector<Vec3> offsets;
    const MonteCarloResult r =
        MonteCarloCovariance(p.cameras, p.X, study.sigma_px, study.trials, seed++, {}, &offsets);
    GateVoxel v;
    v.X = p.X;
    v.cameras = static_cast<int>(p.cameras.size());
    std::vector<Vec3> directions;
    for (const Camera& c : p.cameras) directions.push_back((p.X - c.center()).normalized());
    v.angle_deg = MaxTriangulationAngle(directions) * kGateDegPerRad;
    v.failures = r.failures;
    Mat3 predicted_axes, empirical_axes;
    SortedEigen(r.predicted_covariance, v.predicted, &predicted_axes);
    SortedEigen(r.empirical_covariance, v.empirical, &empirical_axes);
    const int samples = study.trials - r.failures;
    v.pass = samples >= 2;
    for (int a = 0; a < 3; ++a) {
      if (!(std::abs(v.Ratio(a) - 1) <= kGateEigenTolerance[a])) v.pass = false;
      if (samples < 2 || AxisStandardErrorDeg(v.predicted, a, samples) > kGateResolvableDeg) {
        v.axis_deg[a] = kGateNaN;
        continue;
      }
      const double c = std::min(1.0, std::abs(predicted_axes.col(a).dot(empirical_axes.col(a))));
      v.axis_deg[a] = std::acos(c) * kGateDegPerRad;
      if (!(v.axis_deg[a] <= kGateAngleDeg)) v.pass = false;
    }
    v.skew_major = Skewness(offsets, predicted_axes.col(0));
    study.voxels.push_back(v);
  }
  study.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (std::string note = OwnPixelSigmaNote(rig, study.sigma_px); !note.empty())
    study.notes.push_back(note);
  return study;
}

}  // namespace pandora
