#pragma once
/// \file builders.h
/// Geometry a designer should not have to write by hand: rooms (a footprint extruded into walls
/// with door and window gaps, a floor and a ceiling), furniture boxes, people (articulated figures
/// of capsules with standard body proportions) and their walks (way points at a speed, or a seeded
/// random walk that keeps clear of solids and of other walkers). Everything here is plain geometry
/// in metres; the scene reader (scene.cpp, "room" and "person" objects, "walk" and "wander"
/// motions) and `pandora import-plan` build on it. docs/scene-format.md "Rooms and people".

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "analysis/geometry/geometry.h"
#include "analysis/scene/motion.h"

namespace pandora {

using Polygon2 = std::vector<Vec2>;

/// The distance from `p` to the segment from `a` to `b` (to `a` when they coincide).
double DistanceToSegment(const Vec2& p, const Vec2& a, const Vec2& b);

/// Twice the signed area of a polygon (positive: counter-clockwise seen from +z).
double SignedArea2(const Polygon2& polygon);

/// Why `polygon` cannot be a footprint (fewer than 3 points, a repeated point, an edge shorter
/// than 1 mm, two edges crossing or touching, zero area), or empty when it can.
std::string PolygonProblem(const Polygon2& polygon);

/// Triangles of a simple polygon by ear clipping, as indices into `polygon`, counter-clockwise
/// seen from +z whatever the polygon's own orientation.
std::vector<Eigen::Vector3i> TriangulatePolygon(const Polygon2& polygon);

/// The closed prism of a simple polygon between heights z0 < z1 (outward-facing triangles).
TriangleMesh ExtrudePolygon(const Polygon2& polygon, double z0, double z1);

/// The capsule of `radius` whose axis runs from `a` to `b` (a sphere when they coincide).
TriangleMesh CapsuleBetween(const Vec3& a, const Vec3& b, double radius, int segments);

/// A gap in a wall: `offset` metres from the wall's start along its inner face to the gap's near
/// edge, `width` along the wall, from `sill` above the floor up to `sill + height`.
struct WallOpening {
  int wall = 0;  ///< Wall i runs from footprint[i] to footprint[i + 1] (the last one closes it).
  double offset = 0, width = 0.9, sill = 0, height = 2.1;
};

/// A room: walls of `thickness` standing outside the footprint (the footprint is the free inside,
/// the walls' inner faces), from the floor (z = 0) up to `height`; a floor slab below z = 0 and a
/// ceiling slab above `height`, each `slab` thick, covering the walls too.
struct RoomSpec {
  Polygon2 footprint;
  double height = 2.8, thickness = 0.15, slab = 0.2;
  bool floor = true, ceiling = true;
  std::vector<WallOpening> openings;
};

/// One named, closed part of a built room or person ("wall0", "floor", "head", ...).
struct BuiltPart {
  std::string name;
  TriangleMesh mesh;
  /// A capsule's axis ends and the radius of the capsule its tessellation surely contains (a
  /// person's parts; radius 0 for anything else).
  Vec3 axis_a = Vec3::Zero(), axis_b = Vec3::Zero();
  double radius = 0;
};

/// Why `room` cannot be built (its footprint's PolygonProblem, a corner sharper than 10 degrees, a
/// wall shorter than its corners need, an opening off its wall, above the ceiling or overlapping
/// another), with the index of the offending opening in `opening` (-1 when the problem is not an
/// opening's); empty when it can.
std::string RoomProblem(const RoomSpec& room, int* opening);

/// The room's walls (one part per wall, "wall0", "wall1", ...; a wall with gaps is several closed
/// blocks), "floor" and "ceiling". Precondition: RoomProblem(room) is empty.
std::vector<BuiltPart> BuildRoom(const RoomSpec& room);

/// Standard furniture sizes (metres, x by y by height) by type; false when `type` is unknown.
bool FurnitureSize(const std::string& type, Vec3* size);
/// The furniture types FurnitureSize knows, sorted.
std::vector<std::string> FurnitureTypes();

/// A person: `height` metres tall, feet on z = 0 round the origin, facing +x (left is +y), in one
/// of PersonPoses(). Segment lengths and girths are fractions of the height (Drillis and Contini's
/// proportions as tabulated in Winter, Biomechanics and Motor Control of Human Movement, 4th ed.,
/// table 4.1); `girth` scales the radii.
struct PersonSpec {
  double height = 1.75;
  std::string pose = "standing";
  double girth = 1.0;
  int segments = 12;
};

/// "standing", "sitting" (thighs level at knee height: sitting on a seat of 0.25 of the height),
/// "walking" (mid-stride).
const std::vector<std::string>& PersonPoses();

/// The person's parts: "head", "neck", "torso", "pelvis", "upper_arm_l", "forearm_l", "hand_l",
/// the same on the right ("_r"), "thigh_l", "shank_l", "foot_l" and on the right; each a closed
/// capsule (the head a sphere). Precondition: a known pose, height in [0.5, 2.5], girth in
/// [0.5, 2], segments >= 4.
std::vector<BuiltPart> BuildPerson(const PersonSpec& person);

/// A walk along way points (the anchor's x, y, metres) at `speed` m/s from `start_s`, turning to
/// face each leg over `turn_s` seconds at each corner; `closed` walks back to the first point.
struct WalkSpec {
  std::vector<Vec2> path;
  double speed = 1.2, start_s = 0, turn_s = 0.5;
  bool closed = false;
};

/// The keyframes of `walk` for a group placed with its anchor at `anchor` and facing
/// `facing_deg` (degrees counter-clockwise from +x): the move puts the anchor on the path and the
/// yaw turns the group to face along it (yaw unwrapped: never more than half a turn at a corner).
std::vector<std::pair<double, GroupPose>> WalkKeyframes(const WalkSpec& walk, const Vec3& anchor,
                                                        double facing_deg);

/// A seeded random walk: from the anchor's place, legs to points drawn uniformly in `region`'s
/// x, y at `speed`, pausing `pause_s` at each, for `duration_s` seconds; a leg is taken only when
/// a disc of `radius` round the anchor stays clear of every obstacle's footprint and `2 radius`
/// from every other walker at every 0.05 s along it (up to 200 draws per leg; with none free the
/// walker waits 1 s and draws again).
struct WanderSpec {
  Aabb region;
  double duration_s = 30, speed = 1.0, pause_s = 1.0, turn_s = 0.5, radius = 0.3;
  std::uint64_t seed = 1;
};

/// A static obstacle for WanderKeyframes: triangles' footprints (x, y) within the walker's height.
struct Footprint2 {
  std::vector<std::array<Vec2, 3>> triangles;
  /// The smallest distance from `p` to the footprint (0 inside).
  double Distance(const Vec2& p) const;
  /// The smallest distance from the segment a-b to the footprint (0 when it enters it).
  double SegmentDistance(const Vec2& a, const Vec2& b) const;
};

/// Another walker: the anchor's x, y at time t.
struct OtherWalker {
  Vec3 anchor;
  std::vector<std::pair<double, GroupPose>> keyframes;
  Vec2 At(double t) const;
};

/// The keyframes of `wander` for a group at `anchor` facing `facing_deg`. `obstacles` is the
/// footprint of the static solids. Throws std::invalid_argument (naming the reason) when the
/// start itself is not clear.
std::vector<std::pair<double, GroupPose>> WanderKeyframes(const WanderSpec& wander,
                                                          const Vec3& anchor, double facing_deg,
                                                          const Footprint2& obstacles,
                                                          const std::vector<OtherWalker>& others);

}  // namespace pandora
