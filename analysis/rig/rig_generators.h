#pragma once
/// \file rig_generators.h
/// Rig generators (`pandora rig`, docs/rig-generators.md): the layouts a stage builder or a
/// surveillance planner starts from, as cameras in the scene file's look_at form. Light header.
///  - ring: N cameras evenly on a horizontal circle, aimed at a point (a capture stage, a mocap
///  ring);
///  - grid: NX x NY cameras over a rectangle on the ceiling (looking straight down, or aimed) or
///    over a wall (a vertical rectangle above a wall segment, aimed);
///  - along walls: N cameras evenly by length along a polyline of walls, set in from them, aimed at
///    the region ("these walls, N cameras").

#include <string>
#include <vector>

#include "analysis/geometry/geometry.h"

namespace pandora {

struct Scene;

/// One generated camera: an id and a look_at pose (world, metres).
struct GeneratedCamera {
  std::string id;
  Vec3 position = Vec3::Zero();
  Vec3 look_at = Vec3::UnitY();
  Vec3 up = Vec3::UnitZ();
};

/// N cameras on the circle of `radius` about `centre` (horizontal, at centre's height), the first
/// at `start_deg` from +x counter-clockwise, each aimed at `aim`.
std::vector<GeneratedCamera> RingCameras(int count, const Vec3& centre, double radius,
                                         double start_deg, const Vec3& aim,
                                         const std::string& prefix);

/// nx x ny cameras at the cell centres of the rectangle [x0, x1] x [y0, y1] at height z, looking
/// straight down (image up +y) or, with `aim`, at it.
std::vector<GeneratedCamera> CeilingGridCameras(int nx, int ny, const Vec2& min_xy,
                                                const Vec2& max_xy, double z, const Vec3* aim,
                                                const std::string& prefix);

/// nu x nz cameras at the cell centres of the vertical rectangle over the wall segment a -> b (xy)
/// between heights z0 and z1, set `inset` metres in from the wall towards `aim`, aimed at `aim`.
std::vector<GeneratedCamera> WallGridCameras(int nu, int nz, const Vec2& a, const Vec2& b,
                                             double z0, double z1, double inset, const Vec3& aim,
                                             const std::string& prefix);

/// `count` cameras evenly by length along the polyline `walls` (xy corners, at least two) at height
/// z: the k-th at length (k + 1/2) L / count, set `inset` metres in from its wall towards `aim`
/// (perpendicular to the wall), aimed at `aim`.
std::vector<GeneratedCamera> AlongWallsCameras(int count, const std::vector<Vec2>& walls, double z,
                                               double inset, const Vec3& aim,
                                               const std::string& prefix);

/// Moves each generated camera away from the scene's surfaces until its centre is at least
/// `clearance` from every one (a camera near a corner, set in from its own wall, can sit on the
/// next wall's face): along the distance's gradient (away from the nearest point), a few steps for
/// corners. The aim point stays. Returns one note per moved camera; throws InputError naming
/// `option` when a camera cannot be cleared (it is inside a solid thicker than the room allows).
std::vector<std::string> KeepClearance(const Scene& scene, double clearance,
                                       const std::string& option,
                                       std::vector<GeneratedCamera>* cameras);

}  // namespace pandora
