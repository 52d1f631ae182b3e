// The calibration study's bundle adjustment (validation/calibrate.h): every calibrated camera's
// intrinsics and pose and every board pose refined together to the weighted least-squares
// reprojection of the detected corners, by Ceres with automatic derivatives; one camera's pose held
// (the gauge), the board's printed size fixing the scale. Ceres stays in this file.
#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <thread>

#include "validation/calibrate_internal.h"

namespace pandora::calibration_internal {
namespace {

// Intrinsics block: fx fy cx cy c0..c4 (Brown-Conrady: k1 k2 p1 p2 k3; fisheye: k1 k2 k3 k4 and
// one unused).
constexpr int kIntrinsicsSize = 9;

template <typename T>
bool ProjectTemplated(LensModel model, const T* k, const T* p, T* pixel) {
  T xd, yd;
  if (model == LensModel::kFisheye) {
    const T r2 = p[0] * p[0] + p[1] * p[1];
    if (r2 < T(1e-24)) {
      if (!(p[2] > T(0))) return false;
      xd = p[0] / p[2], yd = p[1] / p[2];
    } else {
      const T r = sqrt(r2);
      const T theta = atan2(r, p[2]);
      const T t = theta * theta;
      const T theta_d = theta * (T(1) + t * (k[4] + t * (k[5] + t * (k[6] + t * k[7]))));
      xd = theta_d * p[0] / r, yd = theta_d * p[1] / r;
    }
  } else {
    if (!(p[2] > T(0))) return false;
    const T x = p[0] / p[2], y = p[1] / p[2];
    const T s = x * x + y * y;
    const T radial = T(1) + s * (k[4] + s * (k[5] + s * k[8]));
    xd = x * radial + T(2) * k[6] * x * y + k[7] * (s + T(2) * x * x);
    yd = y * radial + k[6] * (s + T(2) * y * y) + T(2) * k[7] * x * y;
  }
  pixel[0] = k[0] * xd + k[2];
  pixel[1] = k[1] * yd + k[3];
  return true;
}

std::array<double, kIntrinsicsSize> Pack(const Intrinsics& k) {
  if (k.model == LensModel::kFisheye) return {k.fx, k.fy, k.cx, k.cy, k.k1, k.k2, k.k3, k.k4, 0};
  return {k.fx, k.fy, k.cx, k.cy, k.k1, k.k2, k.p1, k.p2, k.k3};
}

void Unpack(const std::array<double, kIntrinsicsSize>& a, Intrinsics* k) {
  k->fx = a[0], k->fy = a[1], k->cx = a[2], k->cy = a[3];
  if (k->model == LensModel::kFisheye) {
    k->k1 = a[4], k->k2 = a[5], k->k3 = a[6], k->k4 = a[7], k->p1 = k->p2 = 0;
  } else {
    k->k1 = a[4], k->k2 = a[5], k->p1 = a[6], k->p2 = a[7], k->k3 = a[8], k->k4 = 0;
  }
}

// Pose block: angle-axis (3) then translation (3).
std::array<double, 6> PackPose(const Eigen::Isometry3d& T) {
  const Eigen::AngleAxisd aa(T.linear());
  const Vec3 r = aa.angle() * aa.axis();
  return {r.x(), r.y(), r.z(), T.translation().x(), T.translation().y(), T.translation().z()};
}

Eigen::Isometry3d UnpackPose(const std::array<double, 6>& a) {
  const Vec3 r(a[0], a[1], a[2]);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const double angle = r.norm();
  if (angle > 0) T.linear() = Eigen::AngleAxisd(angle, r / angle).toRotationMatrix();
  T.translation() = Vec3(a[3], a[4], a[5]);
  return T;
}

// One corner: (project(camera_from_world * world_from_board * (x, y, 0)) - pixel) / sigma.
struct CornerCost {
  LensModel model;
  Vec2 xy, pixel;
  double inv_sigma;
  template <typename T>
  bool operator()(const T* camera, const T* k, const T* board, T* residual) const {
    const T b[3] = {T(xy.x()), T(xy.y()), T(0)};
    T w[3], c[3];
    ceres::AngleAxisRotatePoint(board, b, w);
    for (int i = 0; i < 3; ++i) w[i] += board[3 + i];
    ceres::AngleAxisRotatePoint(camera, w, c);
    for (int i = 0; i < 3; ++i) c[i] += camera[3 + i];
    T uv[2];
    if (!ProjectTemplated(model, k, c, uv)) return false;
    residual[0] = (uv[0] - T(pixel.x())) * T(inv_sigma);
    residual[1] = (uv[1] - T(pixel.y())) * T(inv_sigma);
    return true;
  }
};

// The coefficients held: pinhole design k3 (and fisheye's unused slot).
std::vector<int> HeldCoefficients(LensModel design) {
  if (design == LensModel::kFisheye) return {8};
  if (design == LensModel::kPinhole) return {8};
  return {};
}

// The camera centre -R^T t of a camera_from_world pose block.
Vec3 CentreOfPose(const std::array<double, 6>& a) {
  return -(UnpackPose(a).linear().transpose() * Vec3(a[3], a[4], a[5]));
}

// The adjustment's covariance of each free camera's intrinsics and pose (BundleCamera's std_px,
// rotation_sd_deg, position_sd_mm); NaN when Ceres cannot compute it (a rank-deficient problem).
void CameraCovariances(ceres::Problem* problem, const std::set<int>& used_cameras,
                       std::vector<std::array<double, 6>>* camera_pose,
                       std::vector<std::array<double, kIntrinsicsSize>>* intrinsics,
                       std::vector<BundleCamera>* cameras) {
  ceres::Covariance::Options options;
  options.algorithm_type = ceres::SPARSE_QR;
  options.num_threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  ceres::Covariance covariance(options);
  std::vector<std::pair<const double*, const double*>> blocks;
  for (int c : used_cameras) {
    blocks.push_back({(*intrinsics)[c].data(), (*intrinsics)[c].data()});
    if (!(*cameras)[c].fixed_pose)
      blocks.push_back({(*camera_pose)[c].data(), (*camera_pose)[c].data()});
  }
  const bool ok = covariance.Compute(blocks, problem);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int c : used_cameras) {
    BundleCamera& cam = (*cameras)[c];
    if (!ok) {
      cam.std_px = {nan, nan, nan, nan};
      cam.rotation_sd_deg = cam.position_sd_mm = cam.fixed_pose ? 0 : nan;
      continue;
    }
    double k[kIntrinsicsSize * kIntrinsicsSize];
    covariance.GetCovarianceBlock((*intrinsics)[c].data(), (*intrinsics)[c].data(), k);
    for (int i = 0; i < 4; ++i)
      cam.std_px[i] = std::sqrt(std::max(0.0, k[i * kIntrinsicsSize + i]));
    if (cam.fixed_pose) continue;
    Eigen::Matrix<double, 6, 6, Eigen::RowMajor> P;
    covariance.GetCovarianceBlock((*camera_pose)[c].data(), (*camera_pose)[c].data(), P.data());
    cam.rotation_sd_deg =
        std::sqrt(std::max(0.0, P.topLeftCorner<3, 3>().trace())) * 57.29577951308232;
    // The centre's covariance J P J^T, J = d centre / d pose by central differences.
    Eigen::Matrix<double, 3, 6> J;
    for (int i = 0; i < 6; ++i) {
      std::array<double, 6> plus = (*camera_pose)[c], minus = plus;
      const double h = 1e-6 * std::max(1.0, std::abs(plus[i]));
      plus[i] += h, minus[i] -= h;
      J.col(i) = (CentreOfPose(plus) - CentreOfPose(minus)) / (2 * h);
    }
    const Mat3 C = J * P * J.transpose();
    cam.position_sd_mm = 1e3 * std::sqrt(std::max(0.0, C.trace()));
  }
}

}  // namespace

bool ProjectWithIntrinsics(const Intrinsics& k, const Vec3& p_camera, Vec2* pixel) {
  const std::array<double, kIntrinsicsSize> a = Pack(k);
  double uv[2];
  if (!ProjectTemplated(k.model, a.data(), p_camera.data(), uv)) return false;
  *pixel = Vec2(uv[0], uv[1]);
  return true;
}

BundleResult BundleAdjust(std::vector<BundleCamera>* cameras,
                          std::vector<Eigen::Isometry3d>* world_from_board,
                          const std::vector<BundleView>& views) {
  std::vector<std::array<double, 6>> camera_pose(cameras->size()), board_pose;
  std::vector<std::array<double, kIntrinsicsSize>> intrinsics(cameras->size());
  for (std::size_t c = 0; c < cameras->size(); ++c) {
    camera_pose[c] = PackPose((*cameras)[c].camera_from_world);
    intrinsics[c] = Pack((*cameras)[c].intrinsics);
  }
  for (const Eigen::Isometry3d& T : *world_from_board) board_pose.push_back(PackPose(T));
  ceres::Problem problem;
  BundleResult result;
  std::set<int> used_cameras, used_poses;
  for (const BundleView& v : views) {
    const BundleCamera& cam = (*cameras)[v.camera];
    for (std::size_t i = 0; i < v.corners->pixels.size(); ++i) {
      auto* cost = new ceres::AutoDiffCostFunction<CornerCost, 2, 6, kIntrinsicsSize, 6>(
          new CornerCost{cam.intrinsics.model, v.corners->board_xy[i], v.corners->pixels[i],
                         1.0 / v.corners->sigma_px});
      problem.AddResidualBlock(cost, nullptr, camera_pose[v.camera].data(),
                               intrinsics[v.camera].data(), board_pose[v.pose].data());
      ++result.residuals;
    }
    used_cameras.insert(v.camera);
    used_poses.insert(v.pose);
  }
  for (int c : used_cameras) {
    if ((*cameras)[c].fixed_pose) problem.SetParameterBlockConstant(camera_pose[c].data());
    const std::vector<int> held = HeldCoefficients((*cameras)[c].design);
    std::vector<int> held_indices;
    for (int h : held) held_indices.push_back(h);
    if (!held_indices.empty())
      problem.SetManifold(intrinsics[c].data(),
                          new ceres::SubsetManifold(kIntrinsicsSize, held_indices));
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_SCHUR;
  options.max_num_iterations = 200;
  options.function_tolerance = 1e-14;
  options.parameter_tolerance = 1e-14;
  options.gradient_tolerance = 1e-14;
  options.num_threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  result.converged = summary.termination_type == ceres::CONVERGENCE;
  result.iterations = static_cast<int>(summary.iterations.size());
  result.message = summary.BriefReport();
  CameraCovariances(&problem, used_cameras, &camera_pose, &intrinsics, cameras);
  for (int c : used_cameras) {
    (*cameras)[c].camera_from_world = UnpackPose(camera_pose[c]);
    Unpack(intrinsics[c], &(*cameras)[c].intrinsics);
  }
  for (int k : used_poses) (*world_from_board)[k] = UnpackPose(board_pose[k]);
  // The reprojection RMS in pixels (the cost is in units of each view's noise).
  double sum2 = 0;
  for (const BundleView& v : views) {
    const BundleCamera& cam = (*cameras)[v.camera];
    const Eigen::Isometry3d T = cam.camera_from_world * (*world_from_board)[v.pose];
    for (std::size_t i = 0; i < v.corners->pixels.size(); ++i) {
      Vec2 uv;
      const Vec3 p = T * Vec3(v.corners->board_xy[i].x(), v.corners->board_xy[i].y(), 0);
      if (ProjectWithIntrinsics(cam.intrinsics, p, &uv))
        sum2 += (uv - v.corners->pixels[i]).squaredNorm();
    }
  }
  result.rms_px = result.residuals > 0 ? std::sqrt(sum2 / (2.0 * result.residuals)) : 0;
  return result;
}

}  // namespace pandora::calibration_internal
