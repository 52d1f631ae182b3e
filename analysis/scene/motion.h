#pragma once
/// \file motion.h
/// Moving occluders: people, carts and doors that move through the scene while the cameras stay.
/// A motion moves a group of objects (the objects whose "group" or name it is given) rigidly by a
/// pose: turned by `yaw_deg` about the vertical axis through the group's anchor (the centre of the
/// bottom face of its bounds as the file places it), then shifted by `move`. Motions are keyframed
/// (times and poses, interpolated linearly), named poses, or random placements (an anchor box, a
/// yaw range, seeded). The study's time samples (Scene::TimeSamples) fix every motion's pose at
/// each sample; SceneAtSample gives the scene at one sample. docs/scene-format.md "Moving objects".

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "analysis/geometry/geometry.h"

namespace pandora {

struct Scene;
class RayCaster;
class RigidPartsRayCaster;

/// A rigid pose of a moving group, relative to where the file places it.
struct GroupPose {
  Vec3 move = Vec3::Zero();  ///< Metres, world frame: the anchor's displacement.
  double yaw_deg = 0;  ///< About the world's +z through the anchor, counter-clockwise from above.
};

/// World transform of a pose about `anchor`: X -> anchor + move + Rz(yaw) (X - anchor).
Eigen::Isometry3d PoseTransform(const GroupPose& pose, const Vec3& anchor);

/// One moving group and how it moves.
struct ObjectMotion {
  std::string name;            ///< The group's name (an object's "group", or an object's own name).
  std::vector<int> objects;    ///< Indices into Scene::objects, in file order.
  Vec3 anchor = Vec3::Zero();  ///< Centre of the bottom face of the objects' bounds as placed.
  enum class Kind { kKeyframes, kPoses, kRandom };
  Kind kind = Kind::kKeyframes;
  /// kKeyframes: (time s, pose), times strictly increasing; held constant before the first and
  /// after the last; yaw interpolates linearly in degrees as written (a turn of 350 deg is a turn
  /// of 350).
  std::vector<std::pair<double, GroupPose>> keyframes;
  /// kPoses: named poses in file order.
  std::vector<std::pair<std::string, GroupPose>> poses;
  /// kRandom: the anchor uniform in `box` (metres, world), yaw uniform in [yaw_min, yaw_max] deg,
  /// `samples` draws (the default sample count of the study), reproducible from `seed`.
  Aabb box;
  double yaw_min_deg = 0, yaw_max_deg = 360;
  int samples = 1;
  std::uint64_t seed = 1;

  /// The pose at time `t` (kKeyframes).
  GroupPose AtTime(double t) const;
  /// The i-th random draw (kRandom): the same for the same seed and i, whatever else is drawn.
  GroupPose RandomDraw(int i) const;
};

/// The study's time axis ("study": {"time": ...}): one of explicit times, named poses, or a number
/// of samples (uniform over the keyframes' span, or random draws).
struct TimeStudy {
  std::vector<double> times;       ///< Seconds; keyframed motions are evaluated there.
  std::vector<std::string> poses;  ///< Pose names; motions with named poses take these.
  int samples = 0;                 ///< Uniform over the keyframe span, or random draws.
  /// The camera count the time summaries count against ("seen by >= k cameras"), default 3.
  int min_cameras = 3;
};

/// One sample of the scene in time: its label ("t=1.5 s", "pose 'reach'", "draw 3") and each
/// motion's pose, in Scene::motions order.
struct TimeSample {
  std::string label;
  double time = 0;  ///< Seconds (keyframed samples), else the sample's index.
  std::vector<GroupPose> poses;
  /// True when `time` is seconds (a time axis of times or uniform samples): skinned objects play
  /// their clip at `time`. Named-pose and random-draw samples (false) show them at scene time 0.
  bool timed = false;
  /// The scene time skinned objects take at this sample (seconds).
  double SkinTime() const { return timed ? time : 0.0; }
};

/// `samples`, or for a static scene (none) the one sample "as placed" (no poses).
std::vector<TimeSample> SamplesOrAsPlaced(std::vector<TimeSample> samples);

/// Where Scene::motions[motion] puts its objects at `sample` (world_from_rest); the identity for
/// motion -1 or a sample without poses.
Eigen::Isometry3d MotionTransform(const Scene& scene, int motion, const TimeSample& sample);

/// Index into Scene::motions of the motion that moves object `object`, or -1.
int MotionOfObject(const Scene& scene, int object);

/// Object `object`'s vertices (world) at `sample`: a skinned object's pose at sample.SkinTime()
/// (analysis/scene/skinning.h), then its group's rigid motion; SceneAtSample's mesh of the object.
std::vector<Vec3> ObjectVerticesAt(const Scene& scene, int object, const TimeSample& sample);

/// The scene's parts for ray casting: part 0 holds the objects that do not move, part k + 1 the
/// objects of Scene::motions[k] that are not skinned, part motions.size() + 1 + j the object of
/// Scene::skins[j], each at rest; every triangle keeps its index of Scene::AllTriangles().
/// CasterAtSample(parts, scene, sample) is then the caster of SceneAtSample(scene, sample) without
/// building the rigid parts' BVHs again (only the skinned parts' vertices are replaced).
std::unique_ptr<RigidPartsRayCaster> MakeSceneParts(const Scene& scene);
/// The parts' transforms at `sample` (part 0 the identity; a skinned part its group's motion).
std::vector<Eigen::Isometry3d> PartTransforms(const Scene& scene, const TimeSample& sample);
/// The parts' vertices at `sample` before their transforms: empty for the rigid parts, the skinned
/// pose (world, before the group's motion) for each skinned part.
std::vector<std::vector<Vec3>> PartVertices(const Scene& scene, const TimeSample& sample);
/// parts.At(PartTransforms(scene, sample), PartVertices(scene, sample)); `parts` is
/// MakeSceneParts(scene).
std::unique_ptr<RayCaster> CasterAtSample(const RigidPartsRayCaster& parts, const Scene& scene,
                                          const TimeSample& sample);

}  // namespace pandora
