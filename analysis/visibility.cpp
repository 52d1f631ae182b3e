#include "analysis/visibility.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>

namespace pandora {

const char* ViewResultName(ViewResult result) {
  switch (result) {
    case ViewResult::kSeen: return "seen";
    case ViewResult::kDisabled: return "disabled";
    case ViewResult::kOutOfRange: return "out of range";
    case ViewResult::kNotProjectable: return "not projectable";
    case ViewResult::kOutsideImage: return "outside image";
    case ViewResult::kBackFacing: return "back facing";
    case ViewResult::kOccluded: return "occluded";
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
                                   double scene_scale)
    : cameras_(cameras), caster_(caster), epsilon_(kRelativeEpsilon * scene_scale) {
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
  const Eigen::Isometry3d& cfw = camera_from_world_[camera];
  const Vec3 p_camera = cfw.linear() * X + cfw.translation();
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

ViewResult VisibilityTester::TestGeometry(int camera, const Vec3& X, const Vec3* normal, Ray* segment,
                                          Mat23* d_pixel_d_world) const {
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
