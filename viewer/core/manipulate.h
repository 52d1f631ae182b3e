#pragma once
/// \file manipulate.h
/// Moving cameras, without GL: the translate and rotate gizmo's drag geometry, snap steps, rigid
/// moves of camera groups, picking a camera body under the cursor, and the gamepad's stick mapping
/// (the Pandora paper's fourth power). The viewer turns input into these calls and the results into
/// EditableRig edits.

#include <optional>
#include <vector>

#include "analysis/geometry/ray_caster.h"
#include "analysis/scene/scene.h"

namespace pandora::viewer {

/// The parameter t of the point origin + t * axis (unit axis) nearest to the ray: where a drag
/// along a gizmo's axis handle is. nullopt when the ray is parallel to the axis (within 1e-9 rad).
std::optional<double> AxisParameter(const Ray& ray, const Vec3& origin, const Vec3& axis);

/// The signed angle (radians, right-handed about the unit `axis`) swept about `origin` from where
/// ray `from` meets the plane through `origin` normal to `axis` to where ray `to` meets it: a drag
/// on a gizmo's rotation ring. nullopt when a ray misses the plane or hits it at the origin.
std::optional<double> SweptAngle(const Ray& from, const Ray& to, const Vec3& origin,
                                 const Vec3& axis);

/// `value` rounded to a multiple of `step` (step <= 0: unchanged).
double Snap(double value, double step);

/// A rigid move of a group of cameras: each pose P becomes T P with T = rotate `rotation` about
/// `pivot`, then translate by `move` (world frame). One camera with pivot at its centre turns in
/// place.
std::vector<Eigen::Isometry3d> MoveRigidly(const std::vector<Eigen::Isometry3d>& poses,
                                           const Vec3& pivot, const Vec3& move,
                                           const Mat3& rotation);

/// The camera whose body (a sphere of `radius` metres around its centre) `ray` meets first, or -1.
/// Disabled cameras can be picked too (to turn them back on).
int PickCamera(const Rig& rig, const Ray& ray, double radius);

/// The paper's stick mapping: zero inside the dead zone, then the fourth power of the travel beyond
/// it (|x| from `deadzone` to 1 maps onto 0 to 1), with the stick's sign: fine control near the
/// centre, full speed at the rim. `x` is clamped to [-1, 1].
double StickCurve(double x, double deadzone = 0.1);

/// A gamepad's state (GLFW's gamepad axes: sticks in [-1, 1], y down; triggers in [-1, 1]).
struct GamepadAxes {
  double left_x = 0, left_y = 0, right_x = 0, right_y = 0;
  double left_trigger = -1, right_trigger = -1;
};

/// How far `dt` seconds of stick input move and turn a camera: left stick forward/back and sideways
/// (camera frame, horizontal), triggers down/up (world Z), right stick yaw (about world Z, keeps
/// the horizon level) and pitch (about the camera's x axis); speeds at full deflection. Returns the
/// new world_from_camera.
Eigen::Isometry3d GamepadMove(const Eigen::Isometry3d& world_from_camera, const GamepadAxes& axes,
                              double dt, double metres_per_second, double degrees_per_second);

}  // namespace pandora::viewer
