#pragma once
/// \file navigation.h
/// The viewer's main-view camera, without GL: orbit, pan and dolly around a target point (Z up),
/// and fly (move and turn the eye). What the mouse, the keyboard, the gamepad and a script do to
/// the view is a call here, so it is unit-tested and replayable.

#include "analysis/geometry/geometry.h"
#include "render/render.h"

namespace pandora::viewer {

struct OrbitView {
  Vec3 target = Vec3::Zero();
  double distance = 5.0;   ///< Eye to target, m (kept in [1e-3, 1e5]).
  double yaw_deg = -60.0;  ///< Azimuth of the eye about +Z, from +X towards +Y.
  double pitch_deg =
      30.0;               ///< Elevation of the eye above the target's horizontal plane, [-89, 89].
  double fov_deg = 50.0;  ///< Horizontal field of view.

  Vec3 Eye() const;
  /// Unit vectors of the view: forward (eye to target), right, up (screen up).
  Vec3 Forward() const;
  Vec3 Right() const;
  Vec3 Up() const;
  /// The renderer's view of this camera at width x height pixels.
  RenderView ToRenderView(int width, int height) const;

  /// Turns the eye about the target: `dx_px` right turns the scene with the cursor (yaw decreases
  /// 0.3 degree per pixel), `dy_px` down raises the eye.
  void Orbit(double dx_px, double dy_px);
  /// Moves the target in the view plane so the point under the cursor follows it, for a view
  /// `width_px` wide.
  void Pan(double dx_px, double dy_px, int width_px);
  /// Moves the eye towards the target: distance x 0.85^steps (a wheel notch is one step).
  void Dolly(double steps);
  /// Fly: moves eye and target together by `right`, `up` (world +Z) and `forward` metres.
  void Fly(double right, double up, double forward);
  /// Fly: turns the view about the eye by yaw and pitch degrees (the target moves).
  void Look(double dyaw_deg, double dpitch_deg);

  /// A view of `box` from the south-west, above, that holds the whole box.
  static OrbitView Framing(const Aabb& box, double fov_deg = 50.0);
  /// The view from `from` looking at `at` (a scene's named view).
  static OrbitView FromLookAt(const Vec3& from, const Vec3& at, double fov_deg);
};

}  // namespace pandora::viewer
