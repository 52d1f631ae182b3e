#include "analysis/geometry/visibility.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace pandora {

const char* ViewResultName(ViewResult result) {
  switch (result) {
    case ViewResult::kSeen:
      return "seen";
    case ViewResult::kDisabled:
      return "disabled";
    case ViewResult::kOutOfRange:
      return "out of range";
    case ViewResult::kNotProjectable:
      return "not projectable";
    case ViewResult::kOutsideImage:
      return "outside image";
    case ViewResult::kBackFacing:
      return "back facing";
    case ViewResult::kOccluded:
      return "occluded";
  }
  return "unknown";
}

double PixelDensity(const Mat23& J) {
  // det(J J^T) written out: Eigen's generic small product was a fifth of the field time.
  const double a = J.row(0).squaredNorm();
  const double b = J.row(0).dot(J.row(1));
  const double c = J.row(1).squaredNorm();
  const double det = a * c - b * b;
  if (!(det > 0.0) || !std::isfinite(det)) return 0.0;
  return std::sqrt(std::sqrt(det));
}

VisibilityTester::VisibilityTester(const std::vector<Camera>& cameras, const RayCaster& caster,
                                   double scene_scale, const SurfaceDistance* surfaces)
    : cameras_(cameras),
      caster_(caster),
      surfaces_(surfaces),
      epsilon_(kRelativeEpsilon * scene_scale) {
  camera_from_world_.reserve(cameras_.size());
  const Aabb& bounds = caster.bounds();
  const Vec3 frame_origin = bounds.empty() ? Vec3::Zero() : bounds.center();
  const double radius = 0.5 * bounds.diagonal();
  for (const Camera& c : cameras_) {
    camera_from_world_.push_back(c.camera_from_world());
    rotation_.push_back(camera_from_world_.back().linear());
    float_error_base_.push_back(kFloatErrorFactor * 0x1p-24 *
                                (radius + (c.center() - frame_origin).norm()));
  }
}

ViewResult VisibilityTester::TestGeometryCameraFrame(int camera, const Vec3& X, const Vec3* normal,
                                                     Ray* segment, Mat23* d_pixel_d_camera) const {
  const Camera& cam = cameras_[camera];
  if (!cam.enabled) return ViewResult::kDisabled;
  const Vec3 to_point = X - cam.center();
  const double distance = to_point.norm();
  if (distance < cam.near || distance > cam.far) return ViewResult::kOutOfRange;
  // Written out, summed left to right: TestGeometryBatch evaluates the same expression per lane
  // (Eigen's fixed-size product sums some rows as a + (b + c)).
  const Eigen::Isometry3d& cfw = camera_from_world_[camera];
  const auto& R = cfw.linear();
  const Vec3& t = cfw.translation();
  const Vec3 p_camera(R(0, 0) * X.x() + R(0, 1) * X.y() + R(0, 2) * X.z() + t.x(),
                      R(1, 0) * X.x() + R(1, 1) * X.y() + R(1, 2) * X.z() + t.y(),
                      R(2, 0) * X.x() + R(2, 1) * X.y() + R(2, 2) * X.z() + t.z());
  const std::optional<Vec2> pixel = cam.model.Project(p_camera, d_pixel_d_camera);
  if (!pixel) return ViewResult::kNotProjectable;
  if (!cam.model.InImage(*pixel)) return ViewResult::kOutsideImage;
  if (normal && normal->dot(-to_point) <= 0.0) return ViewResult::kBackFacing;
  if (segment) {
    const double tolerance = Tolerance(camera, distance);
    segment->origin = cam.center();
    segment->direction = to_point / distance;
    segment->t_near = tolerance;
    segment->t_far = std::max(tolerance, distance - tolerance);
  }
  return ViewResult::kSeen;
}

namespace {

// One camera's projection for the batch test: camera_from_world, centre, range and intrinsics.
struct BatchCamera {
  double r[9], t[3];  // camera_from_world, rotation row-major and translation
  double c[3];        // centre, world
  double near, far;
  double fx, fy, cx, cy;  // intrinsics
  double k1, k2, k3, p1, p2, max_radius;
  double u_max, v_max;   // width - 0.5, height - 0.5
  double base, epsilon;  // Tolerance(): float_error_base_[camera] and epsilon_
};

using GeometryBatch = VisibilityTester::GeometryBatch;

// Per point: the tests of TestGeometryCameraFrame (range, projection, image), the occlusion
// segment and the camera-frame Jacobian, into out's arrays at the point's index (the caller lists
// the points that pass in out->index). Every expression is written as the one-point path evaluates
// it (its 3x3 product and Eigen's norm summed left to right, BcDistort, CameraModel::Project,
// Tolerance), so a lane gives the bits of the one-point test; the lanes are independent, without
// branches (ints combined with &, not &&), and vectorise. No FMA contraction: the AVX2 clone does
// not enable FMA.
template <bool kBc>
__attribute__((always_inline)) inline void ProjectLanes(const BatchCamera& P, int n,
                                                        const double* x, const double* y,
                                                        const double* z, GeometryBatch* out,
                                                        unsigned char* ok) {
  // The outputs through restrict pointers hoisted out of the loop: otherwise every store could
  // change `out` or P, and GCC reloads them per point and does not vectorise.
  double* __restrict j0 = out->jac[0];
  double* __restrict j1 = out->jac[1];
  double* __restrict j2 = out->jac[2];
  double* __restrict j3 = out->jac[3];
  double* __restrict j4 = out->jac[4];
  double* __restrict j5 = out->jac[5];
  double* __restrict ox = out->dx;
  double* __restrict oy = out->dy;
  double* __restrict oz = out->dz;
  double* __restrict tn = out->t_near;
  double* __restrict tf = out->t_far;
  const BatchCamera Q = P;
#pragma omp simd
  for (int i = 0; i < n; ++i) {
    const double X = x[i], Y = y[i], Z = z[i];
    const double tx = X - Q.c[0], ty = Y - Q.c[1], tz = Z - Q.c[2];
    const double distance = std::sqrt(tx * tx + ty * ty + tz * tz);
    const double px = Q.r[0] * X + Q.r[1] * Y + Q.r[2] * Z + Q.t[0];
    const double py = Q.r[3] * X + Q.r[4] * Y + Q.r[5] * Z + Q.t[1];
    const double pz = Q.r[6] * X + Q.r[7] * Y + Q.r[8] * Z + Q.t[2];
    const double nx = px / pz, ny = py / pz;
    double dx = nx, dy = ny, d00 = 1, d01 = 0, d10 = 0, d11 = 1;
    int lens = 1;
    if constexpr (kBc) {
      const double s = nx * nx + ny * ny;
      const double radial = 1 + s * (Q.k1 + s * (Q.k2 + s * Q.k3));
      dx = nx * radial + 2 * Q.p1 * nx * ny + Q.p2 * (s + 2 * nx * nx);
      dy = ny * radial + Q.p1 * (s + 2 * ny * ny) + 2 * Q.p2 * nx * ny;
      const double dr = 2 * (Q.k1 + s * (2 * Q.k2 + s * 3 * Q.k3));
      const double cross = dr * nx * ny + 2 * Q.p1 * nx + 2 * Q.p2 * ny;
      d00 = radial + dr * nx * nx + 2 * Q.p1 * ny + 6 * Q.p2 * nx;
      d01 = cross;
      d10 = cross;
      d11 = radial + dr * ny * ny + 6 * Q.p1 * ny + 2 * Q.p2 * nx;
      lens = int(std::sqrt(s) < Q.max_radius) & int(d00 * d11 - d10 * d01 > 0);
    }
    const double u = Q.fx * dx + Q.cx, v = Q.fy * dy + Q.cy;
    ok[i] = static_cast<unsigned char>(int(distance >= Q.near) & int(distance <= Q.far) &
                                       int(pz > 0) & lens & int(u >= -0.5) & int(v >= -0.5) &
                                       int(u <= Q.u_max) & int(v <= Q.v_max));
    // The segment: Tolerance(), then as TestGeometryCameraFrame sets it.
    const double f = Q.base + VisibilityTester::kFloatErrorFactor * 0x1p-24 * distance;
    const double tolerance = f > Q.epsilon ? f : Q.epsilon;
    const double rest = distance - tolerance;
    ox[i] = tx / distance;
    oy[i] = ty / distance;
    oz[i] = tz / distance;
    tn[i] = tolerance;
    tf[i] = tolerance < rest ? rest : tolerance;  // std::max(tolerance, rest)
    const double iz = 1 / pz;
    const double fx = Q.fx * iz, fy = Q.fy * iz;
    const double a0 = fx * d00, b0 = fx * d01, a1 = fy * d10, b1 = fy * d11;
    j0[i] = a0;
    j1[i] = b0;
    j2[i] = -(a0 * nx + b0 * ny);
    j3[i] = a1;
    j4[i] = b1;
    j5[i] = -(a1 * nx + b1 * ny);
  }
}

// The same code twice: 4 doubles wide where the CPU has AVX2 (without FMA, so the same bits), one
// point at a time elsewhere (GCC 12 does not vectorise the mask's conversion with SSE2 alone); the
// build targets baseline x86-64.
template <bool kBc>
__attribute__((target("avx2"))) void ProjectLanesAvx2(const BatchCamera& P, int n, const double* x,
                                                      const double* y, const double* z,
                                                      GeometryBatch* out, unsigned char* ok) {
  ProjectLanes<kBc>(P, n, x, y, z, out, ok);
}
template <bool kBc>
void ProjectLanesBase(const BatchCamera& P, int n, const double* x, const double* y,
                      const double* z, GeometryBatch* out, unsigned char* ok) {
  ProjectLanes<kBc>(P, n, x, y, z, out, ok);
}

bool HaveAvx2() {
  static const bool have = __builtin_cpu_supports("avx2");
  return have;
}

// PixelDensity's expressions lane by lane: Eigen sums a 3-vector's squared norm and dot product
// as x0 + (x1 + x2); a degenerate or non-finite determinant gives 0 (the select keeps the square
// roots of the other lanes exact; both are correctly rounded in scalar and vector code).
__attribute__((always_inline)) inline void DensityLanes(int n, const double* const jac[6],
                                                        float* out) {
  const double* __restrict j0 = jac[0];
  const double* __restrict j1 = jac[1];
  const double* __restrict j2 = jac[2];
  const double* __restrict j3 = jac[3];
  const double* __restrict j4 = jac[4];
  const double* __restrict j5 = jac[5];
  float* __restrict o = out;
#pragma omp simd
  for (int m = 0; m < n; ++m) {
    const double a = j0[m] * j0[m] + (j1[m] * j1[m] + j2[m] * j2[m]);
    const double b = j0[m] * j3[m] + (j1[m] * j4[m] + j2[m] * j5[m]);
    const double c = j3[m] * j3[m] + (j4[m] * j4[m] + j5[m] * j5[m]);
    const double det = a * c - b * b;
    // det > 0 and det <= DBL_MAX (not NaN, not infinite), and the selects, on the bits: with
    // floating-point comparisons and selects GCC keeps branches (it may not make a comparison that
    // can trap unconditional) and does not vectorise the loop.
    std::uint64_t bits;
    std::memcpy(&bits, &det, sizeof(bits));
    const std::uint64_t good = -std::uint64_t(bits - 1 < 0x7fefffffffffffffULL);      // all ones
    const std::uint64_t safe_bits = (bits & good) | (0x3ff0000000000000ULL & ~good);  // else 1.0
    double safe;
    std::memcpy(&safe, &safe_bits, sizeof(safe));
    const float root = static_cast<float>(std::sqrt(std::sqrt(safe)));
    std::uint32_t root_bits;
    std::memcpy(&root_bits, &root, sizeof(root_bits));
    root_bits &= static_cast<std::uint32_t>(good);  // +0.0f where not good
    std::memcpy(o + m, &root_bits, sizeof(root_bits));
  }
}
__attribute__((target("avx2"))) void DensityLanesAvx2(int n, const double* const jac[6],
                                                      float* out) {
  DensityLanes(n, jac, out);
}

}  // namespace

void PixelDensityLanes(int n, const double* const jac[6], float* out) {
  if (HaveAvx2())
    DensityLanesAvx2(n, jac, out);
  else
    DensityLanes(n, jac, out);
}

void VisibilityTester::TestGeometryBatch(int camera, int n, const double* x, const double* y,
                                         const double* z, GeometryBatch* out) const {
  const Camera& cam = cameras_[camera];
  out->count = 0;
  out->origin = cam.center();
  if (!cam.enabled || n <= 0) return;
  if (n > 512) throw std::logic_error("TestGeometryBatch: more than 512 points");
  const Intrinsics& k = cam.model.intrinsics();
  if (k.model == LensModel::kFisheye) {
    int m = 0;
    for (int i = 0; i < n; ++i) {
      Ray segment;
      Mat23 J;
      if (TestGeometryCameraFrame(camera, Vec3(x[i], y[i], z[i]), nullptr, &segment, &J) !=
          ViewResult::kSeen)
        continue;
      out->index[m] = static_cast<std::int16_t>(i);
      out->dx[i] = segment.direction.x();
      out->dy[i] = segment.direction.y();
      out->dz[i] = segment.direction.z();
      out->t_near[i] = segment.t_near;
      out->t_far[i] = segment.t_far;
      for (int r = 0; r < 6; ++r) out->jac[r][i] = J(r / 3, r % 3);
      ++m;
    }
    out->count = m;
    return;
  }
  BatchCamera P;
  const Eigen::Isometry3d& cfw = camera_from_world_[camera];
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) P.r[3 * r + c] = cfw.linear()(r, c);
    P.t[r] = cfw.translation()[r];
  }
  for (int a = 0; a < 3; ++a) P.c[a] = out->origin[a];
  P.near = cam.near;
  P.far = cam.far;
  P.fx = k.fx;
  P.fy = k.fy;
  P.cx = k.cx;
  P.cy = k.cy;
  P.k1 = k.k1;
  P.k2 = k.k2;
  P.k3 = k.k3;
  P.p1 = k.p1;
  P.p2 = k.p2;
  P.max_radius = cam.model.max_radius();
  P.u_max = k.width - 0.5;
  P.v_max = k.height - 0.5;
  P.base = float_error_base_[camera];
  P.epsilon = epsilon_;

  alignas(64) unsigned char ok[512];
  const bool bc = k.model == LensModel::kBrownConrady;
  if (HaveAvx2()) {
    (bc ? ProjectLanesAvx2<true> : ProjectLanesAvx2<false>)(P, n, x, y, z, out, ok);
  } else {
    (bc ? ProjectLanesBase<true> : ProjectLanesBase<false>)(P, n, x, y, z, out, ok);
  }
  int m = 0;
  for (int i = 0; i < n; ++i) {
    out->index[m] = static_cast<std::int16_t>(i);
    m += ok[i];
  }
  out->count = m;
}

ViewResult VisibilityTester::TestGeometry(int camera, const Vec3& X, const Vec3* normal,
                                          Ray* segment, Mat23* d_pixel_d_world) const {
  Mat23 d_pixel_d_camera;
  const ViewResult result = TestGeometryCameraFrame(camera, X, normal, segment,
                                                    d_pixel_d_world ? &d_pixel_d_camera : nullptr);
  if (result == ViewResult::kSeen && d_pixel_d_world) {
    // d(pixel)/d(world) = d(pixel)/d(camera) R_camera_from_world, written out (hot path).
    const Mat3& R = camera_rotation(camera);
    Mat23& out = *d_pixel_d_world;
    for (int r = 0; r < 2; ++r)
      for (int c = 0; c < 3; ++c)
        out(r, c) = d_pixel_d_camera(r, 0) * R(0, c) + d_pixel_d_camera(r, 1) * R(1, c) +
                    d_pixel_d_camera(r, 2) * R(2, c);
  }
  return result;
}

ViewResult VisibilityTester::Test(int camera, const Vec3& X, const Vec3* normal,
                                  Mat23* d_pixel_d_world) const {
  Ray segment;
  const ViewResult r = TestGeometry(camera, X, normal, &segment, d_pixel_d_world);
  if (r != ViewResult::kSeen) return r;
  if (segment.t_far <= segment.t_near) return ViewResult::kSeen;  // X within epsilon of the centre
  return caster_.Occluded(segment) ? ViewResult::kOccluded : ViewResult::kSeen;
}

void VisibilityTester::TestBatch(int camera, const std::vector<Vec3>& points,
                                 std::vector<ViewResult>* results) const {
  results->assign(points.size(), ViewResult::kSeen);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 256),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i)
                        (*results)[i] = Test(camera, points[i]);
                    });
}

}  // namespace pandora
