#pragma once
/// \file pose.h
/// The one Euler-angle convention of camera orientations: the scene file's "euler_deg" {yaw, pitch,
/// roll} (docs/scene-format.md), read by the scene loader and written back by `pandora accept`.
///
///   world_from_camera = Rz(yaw) Ry(-pitch) Rx(roll) R_base
///
/// R_base (all angles zero) looks along world +X with the image's right along -Y and its down along
/// -Z (camera frame as OpenCV: x right, y down, z forward). Positive yaw turns the view left,
/// toward +Y; positive pitch tilts it up, toward +Z; roll turns the image about the optical axis.
/// The other way to aim a camera, LookAt (position, target, up), is in analysis/geometry/camera.h.

#include "analysis/geometry/geometry.h"

namespace pandora {

/// R_base: world_from_camera of the zero angles. Columns: the camera's x, y, z axes in the world,
/// (0, -1, 0), (0, 0, -1), (1, 0, 0).
Mat3 EulerBaseRotation();

/// world_from_camera rotation of yaw, pitch and roll in radians.
Mat3 RotationFromYawPitchRoll(double yaw, double pitch, double roll);

/// The same from degrees (yaw, pitch, roll), each converted as deg * pi / 180.
Mat3 RotationFromYawPitchRollDeg(const Vec3& yaw_pitch_roll_deg);

/// The angles (degrees: yaw, pitch, roll) of a world_from_camera rotation, the inverse of
/// RotationFromYawPitchRollDeg: yaw and roll in (-180, 180], pitch in [-90, 90]. At pitch +-90
/// (gimbal lock) the roll is folded into the yaw and returned as 0.
Vec3 YawPitchRollDeg(const Mat3& world_from_camera);

}  // namespace pandora
