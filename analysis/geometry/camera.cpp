/// \file camera.cpp
/// Camera models: projection with analytic Jacobians, inversion of the distortion by safeguarded
/// Newton iterations, the monotonic domain of the radial maps and the field of view of the image.

#include "analysis/geometry/camera.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "analysis/util/units.h"

namespace pandora {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// ---------------------------------------------------------------------------------------------
// Real roots of polynomials (coefficients in ascending order of degree).

double EvalPoly(const std::vector<double>& c, double x) {
  double y = 0;
  for (auto it = c.rbegin(); it != c.rend(); ++it) y = y * x + *it;
  return y;
}

std::vector<double> Derivative(const std::vector<double>& c) {
  std::vector<double> d;
  for (size_t i = 1; i < c.size(); ++i) d.push_back(static_cast<double>(i) * c[i]);
  return d;
}

int Sign(double v) { return (v > 0) - (v < 0); }

// Root of `c` in (a, b) where c(a) and c(b) have opposite non-zero signs, by bisection down to
// adjacent doubles (at most ~2100 halvings over the whole double range).
double Bisect(const std::vector<double>& c, double a, double b) {
  const int sign_a = Sign(EvalPoly(c, a));
  for (int i = 0; i < 4200; ++i) {
    const double m = a + 0.5 * (b - a);
    if (m <= a || m >= b) break;
    const double pm = EvalPoly(c, m);
    if (pm == 0) return m;
    (Sign(pm) == sign_a ? a : b) = m;
  }
  return std::abs(EvalPoly(c, a)) <= std::abs(EvalPoly(c, b)) ? a : b;
}

// Real roots of `c` in the open interval (lo, hi), ascending; `hi` may be +infinity. The polynomial
// is monotonic between consecutive real roots of its derivative (found recursively), so each such
// interval holds at most one root, bracketed and bisected. A root where the polynomial touches zero
// without changing sign is reported only when a stationary point evaluates to exactly zero.
std::vector<double> RealRoots(std::vector<double> c, double lo, double hi) {
  while (!c.empty() && c.back() == 0) c.pop_back();
  std::vector<double> roots;
  const int degree = static_cast<int>(c.size()) - 1;
  if (degree <= 0) return roots;
  if (degree == 1) {
    const double r = -c[0] / c[1];
    if (r > lo && r < hi) roots.push_back(r);
    return roots;
  }
  std::vector<double> knots = {lo};
  for (double k : RealRoots(Derivative(c), lo, hi)) knots.push_back(k);
  knots.push_back(hi);
  for (size_t i = 0; i + 1 < knots.size(); ++i) {
    const double a = knots[i];
    double b = knots[i + 1];
    const double pa = EvalPoly(c, a);
    if (pa == 0) {
      if (a > lo && (roots.empty() || roots.back() < a)) roots.push_back(a);
      continue;
    }
    if (std::isinf(b)) {
      // Monotonic up to infinity: a root exists iff the sign at infinity differs. Grow a bracket.
      if (Sign(pa) == Sign(c.back())) continue;
      b = a + std::max(1.0, std::abs(a));
      while (std::isfinite(b) && Sign(EvalPoly(c, b)) == Sign(pa)) b = a + 2 * (b - a);
      if (!std::isfinite(b)) continue;
      if (EvalPoly(c, b) == 0) {
        roots.push_back(b);
        continue;
      }
    }
    const double pb = EvalPoly(c, b);
    if (pb != 0 && Sign(pb) != Sign(pa)) roots.push_back(Bisect(c, a, b));
    // pb == 0 at an inner knot is reported as the next interval's start.
  }
  return roots;
}

// Smallest positive real root of `c`, or +infinity.
double SmallestPositiveRoot(const std::vector<double>& c) {
  const std::vector<double> roots = RealRoots(c, 0.0, kInf);
  return roots.empty() ? kInf : roots.front();
}

// ---------------------------------------------------------------------------------------------
// Safeguarded Newton for a scalar increasing function.

// Solves f(x) = target for x in [lo, hi] where f is increasing there and f(lo) <= target <= f(hi).
// `fn(x, &f, &df)` evaluates f and f'. Newton steps that leave the shrinking bracket, or a
// non-positive slope, fall back to bisection, so the iteration always converges.
template <typename Fn>
double SolveIncreasing(const Fn& fn, double target, double lo, double hi, double guess) {
  double x = std::clamp(guess, lo, hi);
  for (int i = 0; i < 300; ++i) {
    double f = 0, df = 0;
    fn(x, &f, &df);
    const double g = f - target;
    if (g == 0) return x;
    (g < 0 ? lo : hi) = x;
    double next = x - g / df;
    if (!(df > 0) || !(next > lo && next < hi)) next = lo + 0.5 * (hi - lo);
    if (std::abs(next - x) <= 4e-16 * std::abs(next) || hi - lo <= 4e-16 * std::abs(hi)) {
      return next;
    }
    x = next;
  }
  return x;
}

// ---------------------------------------------------------------------------------------------
// Brown-Conrady.

// Radial factor R(s) = 1 + k1 s + k2 s^2 + k3 s^3 with s = r^2.
double BcRadial(const Intrinsics& k, double s) { return 1 + s * (k.k1 + s * (k.k2 + s * k.k3)); }
// dR/ds.
double BcRadialDs(const Intrinsics& k, double s) { return k.k1 + s * (2 * k.k2 + s * 3 * k.k3); }
// d(r R(r^2))/dr = 1 + 3 k1 s + 5 k2 s^2 + 7 k3 s^3.
double BcRadialSlope(const Intrinsics& k, double s) {
  return 1 + s * (3 * k.k1 + s * (5 * k.k2 + s * 7 * k.k3));
}

// Distortion map (x, y) -> (x_d, y_d) of normalized coordinates and its 2x2 Jacobian.
Vec2 BcDistort(const Intrinsics& k, const Vec2& p, Eigen::Matrix2d* jacobian) {
  const double x = p.x(), y = p.y();
  const double s = x * x + y * y;
  const double radial = BcRadial(k, s);
  const Vec2 d(x * radial + 2 * k.p1 * x * y + k.p2 * (s + 2 * x * x),
               y * radial + k.p1 * (s + 2 * y * y) + 2 * k.p2 * x * y);
  if (jacobian != nullptr) {
    const double dr = 2 * BcRadialDs(k, s);  // d(radial)/dx = dr * x.
    const double cross = dr * x * y + 2 * k.p1 * x + 2 * k.p2 * y;
    // Element-wise on purpose: GCC 12.2 at -O3 drops the stores of a comma initializer through
    // this pointer once inlined into a caller that initialised the matrix (Eigen 3.4.0).
    (*jacobian)(0, 0) = radial + dr * x * x + 2 * k.p1 * y + 6 * k.p2 * x;
    (*jacobian)(0, 1) = cross;
    (*jacobian)(1, 0) = cross;
    (*jacobian)(1, 1) = radial + dr * y * y + 6 * k.p1 * y + 2 * k.p2 * x;
  }
  return d;
}

// True when normalized point `p` lies in the Brown-Conrady valid domain.
bool BcInDomain(const Intrinsics& k, double max_radius, const Vec2& p) {
  if (!(p.norm() < max_radius)) return false;
  Eigen::Matrix2d jacobian;
  BcDistort(k, p, &jacobian);
  return jacobian.determinant() > 0;
}

// ---------------------------------------------------------------------------------------------
// Fisheye.

// theta_d / theta = 1 + k1 t + k2 t^2 + k3 t^3 + k4 t^4 with t = theta^2, and its t-derivative.
double FisheyePoly(const Intrinsics& k, double t) {
  return 1 + t * (k.k1 + t * (k.k2 + t * (k.k3 + t * k.k4)));
}
double FisheyePolyDt(const Intrinsics& k, double t) {
  return k.k1 + t * (2 * k.k2 + t * (3 * k.k3 + t * 4 * k.k4));
}
// d(theta_d)/d(theta) = 1 + 3 k1 t + 5 k2 t^2 + 7 k3 t^3 + 9 k4 t^4.
double FisheyeSlope(const Intrinsics& k, double t) {
  return 1 + t * (3 * k.k1 + t * (5 * k.k2 + t * (7 * k.k3 + t * 9 * k.k4)));
}

// S = sin(theta)/theta and dS/dt with t = theta^2, given sin and cos of theta (computed by the
// caller from the point, which keeps them accurate near theta = pi). Small angles use the series
// S = sum (-t)^n / (2n+1)!, which avoids the cancellation in (theta cos - sin) / (2 theta^3).
void SinOverTheta(double theta, double sin_theta, double cos_theta, double* s, double* s_t) {
  if (theta < 0.5) {
    const double t = theta * theta;
    double a = -1.0 / 6.0, sum = 0, dsum = 0;  // a_n = (-1)^n t^(n-1) / (2n+1)!
    for (int n = 1; n <= 10; ++n) {
      sum += a;
      dsum += n * a;
      a *= -t / ((2.0 * n + 2) * (2.0 * n + 3));
    }
    *s = 1 + t * sum;
    *s_t = dsum;
  } else {
    *s = sin_theta / theta;
    *s_t = (theta * cos_theta - sin_theta) / (2 * theta * theta * theta);
  }
}

// ---------------------------------------------------------------------------------------------
// Field of view.

struct FieldBounds {
  double max_angle = 0;
  Eigen::Vector4d normalized;  // x_min, x_max, y_min, y_max
};

// Maximizes `f` on [lo, hi] by golden-section search (f unimodal there); returns nothing, the
// caller records every evaluation.
template <typename Fn>
void GoldenSectionMax(const Fn& f, double lo, double hi, int iterations) {
  const double g = 0.5 * (std::sqrt(5.0) - 1);
  double a = lo, b = hi;
  double c = b - g * (b - a), d = a + g * (b - a);
  double fc = f(c), fd = f(d);
  for (int i = 0; i < iterations; ++i) {
    if (fc >= fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - g * (b - a);
      fc = f(c);
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + g * (b - a);
      fd = f(d);
    }
  }
}

// Unprojects the image border densely. The angle and the normalized coordinates of the rays through
// the image reach their extremes on the border (the undistortion is a homeomorphism of the domain,
// so the image of the rectangle is bounded by the image of its border; the field angle grows with
// the distorted radius, a convex function of the pixel). Extremes at corners are sampled exactly;
// each sampled local extremum inside an edge (for radial distortion, where a principal axis crosses
// the border) is refined by golden-section search. A relative margin of 1e-6 is added.
FieldBounds ComputeFieldBounds(const CameraModel& model) {
  constexpr int kSamplesPerEdge = 256;
  constexpr int kRefineIterations = 40;  // Shrinks two sample spacings by 0.618^40 ~ 4e-9.
  constexpr double kRelativeMargin = 1e-6;
  const Intrinsics& k = model.intrinsics();
  const double x0 = -0.5, x1 = k.width - 0.5, y0 = -0.5, y1 = k.height - 0.5;
  const std::array<std::pair<Vec2, Vec2>, 4> edges = {{{Vec2(x0, y0), Vec2(x1, y0)},
                                                       {Vec2(x1, y0), Vec2(x1, y1)},
                                                       {Vec2(x1, y1), Vec2(x0, y1)},
                                                       {Vec2(x0, y1), Vec2(x0, y0)}}};
  double max_angle = 0;
  // x_min, x_max, y_min, y_max.
  Eigen::Vector4d ext(kInf, -kInf, kInf, -kInf);
  // Some border pixel does not unproject.
  bool outside_domain = false;
  // Some ray has z <= 0: normalized coordinates are unbounded.
  bool behind = false;

  if (k.model == LensModel::kPinhole) {
    // Closed form: x / z = (u - cx) / fx is affine in the pixel, so its extremes over the image
    // border lie at the corners, and so does the largest angle from the axis (the largest
    // |(x, y) / z|). No sampling: a rig of 1000 cameras loads in milliseconds.
    ext = Eigen::Vector4d((x0 - k.cx) / k.fx, (x1 - k.cx) / k.fx, (y0 - k.cy) / k.fy,
                          (y1 - k.cy) / k.fy);
    if (ext(0) > ext(1)) std::swap(ext(0), ext(1));  // a negative focal length mirrors
    if (ext(2) > ext(3)) std::swap(ext(2), ext(3));
    const double far_x = std::max(std::abs(ext(0)), std::abs(ext(1)));
    const double far_y = std::max(std::abs(ext(2)), std::abs(ext(3)));
    FieldBounds bounds;
    bounds.max_angle = std::min(kPi, std::atan(std::hypot(far_x, far_y)) * (1 + kRelativeMargin));
    if (ext.allFinite()) {
      bounds.normalized = ext + Eigen::Vector4d(-kRelativeMargin * far_x, kRelativeMargin * far_x,
                                                -kRelativeMargin * far_y, kRelativeMargin * far_y);
    } else {
      bounds.normalized = Eigen::Vector4d(-kInf, kInf, -kInf, kInf);
    }
    return bounds;
  }

  // Records the ray through `pixel`; returns (angle, x/z, y/z), or nullopt outside the domain.
  auto sample = [&](const Vec2& pixel) -> std::optional<Eigen::Vector3d> {
    const std::optional<Vec3> ray = model.Unproject(pixel);
    if (!ray) {
      outside_domain = true;
      return std::nullopt;
    }
    const double angle = std::atan2(ray->head<2>().norm(), ray->z());
    max_angle = std::max(max_angle, angle);
    if (ray->z() <= 0) {
      behind = true;  // Only the angle is meaningful.
      return Eigen::Vector3d(angle, kNaN, kNaN);
    }
    const double x = ray->x() / ray->z(), y = ray->y() / ray->z();
    ext = Eigen::Vector4d(std::min(ext(0), x), std::max(ext(1), x), std::min(ext(2), y),
                          std::max(ext(3), y));
    return Eigen::Vector3d(angle, x, y);
  };

  for (const auto& [a, b] : edges) {
    auto at = [&, a = a, b = b](double f) -> Vec2 { return a + f * (b - a); };
    std::vector<std::optional<Eigen::Vector3d>> q(kSamplesPerEdge + 1);
    for (int i = 0; i <= kSamplesPerEdge; ++i) {
      q[i] = sample(at(static_cast<double>(i) / kSamplesPerEdge));
    }
    // Quantity (component, sign): maximize sign * q(component).
    const std::array<std::pair<int, double>, 5> quantities = {
        {{0, 1.0}, {1, 1.0}, {1, -1.0}, {2, 1.0}, {2, -1.0}}};
    for (const auto& [component, sign] : quantities) {
      for (int i = 1; i < kSamplesPerEdge; ++i) {
        if (!q[i - 1] || !q[i] || !q[i + 1]) continue;
        const double prev = sign * (*q[i - 1])(component), cur = sign * (*q[i])(component),
                     next = sign * (*q[i + 1])(component);
        if (!(cur > prev && cur >= next)) continue;
        auto objective = [&, component = component, sign = sign](double f) {
          const std::optional<Eigen::Vector3d> v = sample(at(f));
          return v ? sign * (*v)(component) : -kInf;
        };
        GoldenSectionMax(objective, static_cast<double>(i - 1) / kSamplesPerEdge,
                         static_cast<double>(i + 1) / kSamplesPerEdge, kRefineIterations);
      }
    }
  }

  if (outside_domain) {
    // Part of the image lies beyond the image of the valid domain: bound by the domain edge.
    const double r = model.max_radius();
    if (k.model == LensModel::kFisheye) {
      max_angle = std::max(max_angle, r);
      const double t = r < kPi / 2 ? std::tan(r) : kInf;
      ext = Eigen::Vector4d(std::min(ext(0), -t), std::max(ext(1), t), std::min(ext(2), -t),
                            std::max(ext(3), t));
    } else {
      max_angle = std::max(max_angle, std::atan(r));
      ext = Eigen::Vector4d(std::min(ext(0), -r), std::max(ext(1), r), std::min(ext(2), -r),
                            std::max(ext(3), r));
    }
  }

  FieldBounds bounds;
  bounds.max_angle = std::min(kPi, max_angle * (1 + kRelativeMargin));
  if (!behind && bounds.max_angle < kPi / 2 && ext.allFinite()) {
    const double pad_x = kRelativeMargin * std::max(std::abs(ext(0)), std::abs(ext(1)));
    const double pad_y = kRelativeMargin * std::max(std::abs(ext(2)), std::abs(ext(3)));
    bounds.normalized = ext + Eigen::Vector4d(-pad_x, pad_x, -pad_y, pad_y);
  } else {
    bounds.normalized = Eigen::Vector4d(-kInf, kInf, -kInf, kInf);
  }
  return bounds;
}

}  // namespace

const char* LensModelName(LensModel model) {
  switch (model) {
    case LensModel::kPinhole:
      return "pinhole";
    case LensModel::kBrownConrady:
      return "brown_conrady";
    case LensModel::kFisheye:
      return "fisheye";
  }
  return "unknown";
}

std::optional<LensModel> LensModelFromName(const std::string& name) {
  for (LensModel m : {LensModel::kPinhole, LensModel::kBrownConrady, LensModel::kFisheye})
    if (name == LensModelName(m)) return m;
  return std::nullopt;
}

const char* const kLensCoefficientNames[6] = {"k1", "k2", "p1", "p2", "k3", "k4"};

bool LensHasCoefficient(LensModel model, int i) {
  if (model == LensModel::kBrownConrady) return i >= 0 && i <= 4;
  if (model == LensModel::kFisheye) return i == 0 || i == 1 || i == 4 || i == 5;
  return false;
}

double FocalFromHfov(double hfov_rad, int width, LensModel model) {
  const double half_width = 0.5 * width;
  if (model == LensModel::kFisheye) return half_width / (0.5 * hfov_rad);
  return half_width / std::tan(0.5 * hfov_rad);
}

double HfovFromFocal(double fx, int width, LensModel model) {
  const double half_width = 0.5 * width;
  if (model == LensModel::kFisheye) return 2 * half_width / fx;
  return 2 * std::atan(half_width / fx);
}

double FocalFromLens(double focal_mm, double sensor_width_mm, int width) {
  return focal_mm * width / sensor_width_mm;
}

CameraModel::CameraModel(const Intrinsics& intrinsics) : k_(intrinsics) {
  switch (k_.model) {
    case LensModel::kPinhole:
      max_radius_ = kInf;
      break;
    case LensModel::kBrownConrady:
      // First stationary point of r -> r R(r^2), in s = r^2.
      max_radius_ = std::sqrt(SmallestPositiveRoot({1, 3 * k_.k1, 5 * k_.k2, 7 * k_.k3}));
      break;
    case LensModel::kFisheye:
      // First stationary point of theta -> theta_d, in t = theta^2; at most pi.
      max_radius_ = std::min(
          kPi, std::sqrt(SmallestPositiveRoot({1, 3 * k_.k1, 5 * k_.k2, 7 * k_.k3, 9 * k_.k4})));
      break;
  }
  const FieldBounds bounds = ComputeFieldBounds(*this);
  max_field_angle_ = bounds.max_angle;
  normalized_bounds_ = bounds.normalized;
}

std::optional<Vec2> CameraModel::Project(const Vec3& p, Mat23* d_pixel_d_point) const {
  if (!p.allFinite()) return std::nullopt;
  const double X = p.x(), Y = p.y(), Z = p.z();

  if (k_.model == LensModel::kFisheye) {
    const double r = std::hypot(X, Y);
    const double rho = std::hypot(r, Z);
    if (rho == 0) return std::nullopt;
    const double theta = std::atan2(r, Z);
    if (theta >= max_radius_) return std::nullopt;
    const double sin_theta = r / rho, cos_theta = Z / rho;
    const double t = theta * theta;
    const double poly = FisheyePoly(k_, t);
    double s = 0, s_t = 0;
    SinOverTheta(theta, sin_theta, cos_theta, &s, &s_t);
    // pixel - c = f (X, Y) h with h = theta_d / r = F(theta) / rho, F = theta_d / sin(theta),
    // smooth on the axis (F(0) = 1).
    const double big_f = poly / s;
    const double h = big_f / rho;
    if (d_pixel_d_point != nullptr) {
      // E = F'(theta) / sin(theta) = 2 (P_t S - P S_t) / S^3, finite on the axis.
      const double e = 2 * (FisheyePolyDt(k_, t) * s - poly * s_t) / (s * s * s);
      const double rho2 = rho * rho;
      // grad h = ((X, Y) / rho (E cos - F) / rho^2, -(E sin^2 + F cos) / rho^2).
      const double a = (e * cos_theta - big_f) / (rho2 * rho);
      const Vec3 grad_h(X * a, Y * a, -(e * sin_theta * sin_theta + big_f * cos_theta) / rho2);
      d_pixel_d_point->row(0) = k_.fx * (X * grad_h.transpose() + Eigen::RowVector3d(h, 0, 0));
      d_pixel_d_point->row(1) = k_.fy * (Y * grad_h.transpose() + Eigen::RowVector3d(0, h, 0));
    }
    return Vec2(k_.fx * X * h + k_.cx, k_.fy * Y * h + k_.cy);
  }

  if (!(Z > 0)) return std::nullopt;
  const Vec2 n(X / Z, Y / Z);
  Vec2 d = n;
  Eigen::Matrix2d dd_dn = Eigen::Matrix2d::Identity();
  if (k_.model == LensModel::kBrownConrady) {
    if (!(n.norm() < max_radius_)) return std::nullopt;
    d = BcDistort(k_, n, &dd_dn);
    if (!(dd_dn.determinant() > 0)) return std::nullopt;
  }
  if (d_pixel_d_point != nullptr) {
    // diag(fx, fy) * dd_dn * dn_dp with dn_dp = [1/Z 0 -x/Z; 0 1/Z -y/Z], written out (the
    // generic Eigen product showed up in profiles of the field evaluation).
    // Everything in locals first: a store through the output pointer could alias the intrinsics,
    // which would force them to be reloaded after every store.
    const double iz = 1 / Z;
    const double fx = k_.fx * iz, fy = k_.fy * iz;
    const double a0 = fx * dd_dn(0, 0), b0 = fx * dd_dn(0, 1);
    const double a1 = fy * dd_dn(1, 0), b1 = fy * dd_dn(1, 1);
    const double c0 = -(a0 * n.x() + b0 * n.y()), c1 = -(a1 * n.x() + b1 * n.y());
    Mat23& J = *d_pixel_d_point;
    J(0, 0) = a0;
    J(0, 1) = b0;
    J(0, 2) = c0;
    J(1, 0) = a1;
    J(1, 1) = b1;
    J(1, 2) = c1;
  }
  return Vec2(k_.fx * d.x() + k_.cx, k_.fy * d.y() + k_.cy);
}

std::optional<Vec3> CameraModel::Unproject(const Vec2& pixel) const {
  const Vec2 d((pixel.x() - k_.cx) / k_.fx, (pixel.y() - k_.cy) / k_.fy);
  if (!d.allFinite()) return std::nullopt;
  const double rd = d.norm();

  switch (k_.model) {
    case LensModel::kPinhole:
      return Vec3(d.x(), d.y(), 1).normalized();

    case LensModel::kFisheye: {
      auto theta_d = [&](double theta, double* f, double* df) {
        const double t = theta * theta;
        *f = theta * FisheyePoly(k_, t);
        *df = FisheyeSlope(k_, t);
      };
      double rd_max = 0, unused = 0;
      theta_d(max_radius_, &rd_max, &unused);
      if (!(rd < rd_max)) return std::nullopt;
      if (rd == 0) return Vec3(0, 0, 1);
      const double theta = SolveIncreasing(theta_d, rd, 0.0, max_radius_, rd);
      if (!(theta < max_radius_)) return std::nullopt;
      const double sin_theta = std::sin(theta);
      return Vec3(sin_theta * d.x() / rd, sin_theta * d.y() / rd, std::cos(theta)).normalized();
    }

    case LensModel::kBrownConrady: {
      // 1. Radial-only initial guess: solve r R(r^2) = r_d on [0, max_radius).
      auto radial = [&](double r, double* f, double* df) {
        const double s = r * r;
        *f = r * BcRadial(k_, s);
        *df = BcRadialSlope(k_, s);
      };
      double f = 0, df = 0;
      double hi = max_radius_;
      double r0 = 0;
      if (std::isfinite(hi)) {
        radial(hi, &f, &df);
        if (rd >= f) {
          // Beyond the image of the domain edge; only tangential terms can bring it back inside.
          if (k_.p1 == 0 && k_.p2 == 0) return std::nullopt;
          r0 = hi * (1 - 1e-6);
        } else {
          r0 = SolveIncreasing(radial, rd, 0.0, hi, rd);
        }
      } else {
        // No stationary point: r R(r^2) increases without bound. Grow a bracket.
        hi = std::max(1.0, rd);
        for (radial(hi, &f, &df); f < rd; radial(hi, &f, &df)) {
          hi *= 2;
          if (!std::isfinite(hi)) return std::nullopt;
        }
        r0 = SolveIncreasing(radial, rd, 0.0, hi, rd);
      }
      Vec2 n = rd > 0 ? Vec2(d * (r0 / rd)) : Vec2::Zero();

      // 2. Newton on the full 2D map with step halving, staying inside the domain.
      Eigen::Matrix2d jacobian;
      Vec2 residual = BcDistort(k_, n, &jacobian) - d;
      for (int iter = 0; iter < 50 && residual.norm() > 0; ++iter) {
        const double det = jacobian.determinant();
        if (!(det > 0)) break;
        const Vec2 step = jacobian.inverse() * residual;
        if (step.norm() <= 1e-16 * (1 + n.norm())) break;  // Converged to rounding.
        bool accepted = false;
        for (double scale = 1; scale > 1e-9; scale *= 0.5) {
          const Vec2 trial = n - scale * step;
          if (!BcInDomain(k_, max_radius_, trial)) continue;
          Eigen::Matrix2d trial_jacobian;
          const Vec2 trial_residual = BcDistort(k_, trial, &trial_jacobian) - d;
          if (trial_residual.norm() < residual.norm()) {
            n = trial;
            residual = trial_residual;
            jacobian = trial_jacobian;
            accepted = true;
            break;
          }
        }
        if (!accepted) break;  // No further decrease: converged to rounding, or stuck.
      }
      if (!(residual.norm() < 1e-10) || !BcInDomain(k_, max_radius_, n)) return std::nullopt;
      return Vec3(n.x(), n.y(), 1).normalized();
    }
  }
  return std::nullopt;
}

std::optional<Vec2> Camera::Project(const Vec3& p_world, Mat23* d_pixel_d_world) const {
  const Mat3 camera_from_world_rotation = world_from_camera.linear().transpose();
  const Vec3 p_camera = camera_from_world_rotation * (p_world - world_from_camera.translation());
  Mat23 d_pixel_d_camera;
  const std::optional<Vec2> pixel =
      model.Project(p_camera, d_pixel_d_world != nullptr ? &d_pixel_d_camera : nullptr);
  if (pixel && d_pixel_d_world != nullptr) {
    *d_pixel_d_world = d_pixel_d_camera * camera_from_world_rotation;
  }
  return pixel;
}

std::optional<Eigen::Isometry3d> LookAt(const Vec3& position, const Vec3& target, const Vec3& up) {
  const Vec3 forward = target - position;
  const double forward_norm = forward.norm();
  const double up_norm = up.norm();
  if (!(forward_norm > 0) || !(up_norm > 0) || !forward.allFinite() || !up.allFinite()) {
    return std::nullopt;
  }
  const Vec3 z = forward / forward_norm;
  const Vec3 x_unnormalized = z.cross(up / up_norm);  // Norm is sin(angle between z and up).
  const double sin_angle = x_unnormalized.norm();
  if (!(sin_angle > 1e-9)) return std::nullopt;
  const Vec3 x = x_unnormalized / sin_angle;
  const Vec3 y = z.cross(x);  // Opposite the component of `up` orthogonal to z.
  Eigen::Isometry3d world_from_camera = Eigen::Isometry3d::Identity();
  world_from_camera.linear().col(0) = x;
  world_from_camera.linear().col(1) = y;
  world_from_camera.linear().col(2) = z;
  world_from_camera.translation() = position;
  return world_from_camera;
}

bool SameCameraGeometry(const Camera& a, const Camera& b) {
  const Intrinsics& p = a.model.intrinsics();
  const Intrinsics& q = b.model.intrinsics();
  return a.enabled == b.enabled && a.world_from_camera.matrix() == b.world_from_camera.matrix() &&
         a.near == b.near && a.far == b.far && a.pixel_sigma == b.pixel_sigma &&
         p.width == q.width && p.height == q.height && p.fx == q.fx && p.fy == q.fy &&
         p.cx == q.cx && p.cy == q.cy && p.model == q.model && p.k1 == q.k1 && p.k2 == q.k2 &&
         p.p1 == q.p1 && p.p2 == q.p2 && p.k3 == q.k3 && p.k4 == q.k4;
}

}  // namespace pandora
