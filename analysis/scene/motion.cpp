#include "analysis/scene/motion.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "analysis/geometry/ray_caster.h"
#include "analysis/scene/scene.h"
#include "analysis/util/seeded.h"
#include "analysis/util/units.h"

namespace pandora {
namespace {

std::string SixDigits(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}

}  // namespace

Eigen::Isometry3d PoseTransform(const GroupPose& pose, const Vec3& anchor) {
  const double a = pose.yaw_deg * kPi / 180.0;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(a, Vec3::UnitZ()).toRotationMatrix();
  T.translation() = anchor + pose.move - T.linear() * anchor;
  return T;
}

GroupPose ObjectMotion::AtTime(double t) const {
  if (keyframes.empty()) return {};
  if (!(t > keyframes.front().first)) return keyframes.front().second;
  if (!(t < keyframes.back().first)) return keyframes.back().second;
  const auto next = std::upper_bound(keyframes.begin(), keyframes.end(), t,
                                     [](double v, const auto& k) { return v < k.first; });
  const auto prev = next - 1;
  const double w = (t - prev->first) / (next->first - prev->first);
  GroupPose p;
  p.move = (1 - w) * prev->second.move + w * next->second.move;
  p.yaw_deg = (1 - w) * prev->second.yaw_deg + w * next->second.yaw_deg;
  return p;
}

GroupPose ObjectMotion::RandomDraw(int i) const {
  GroupPose p;
  Vec3 at;
  for (int k = 0; k < 3; ++k)
    at[k] = box.min[k] +
            SeededUniform(seed, std::uint64_t(i), std::uint64_t(k)) * (box.max[k] - box.min[k]);
  p.move = at - anchor;
  p.yaw_deg = yaw_min_deg + SeededUniform(seed, std::uint64_t(i), 3) * (yaw_max_deg - yaw_min_deg);
  return p;
}

std::vector<TimeSample> Scene::TimeSamples() const {
  std::vector<TimeSample> out;
  if (!Animated()) return out;
  bool any_keyframes = false, any_poses = false;
  int random_samples = 0;
  double t0 = 0, t1 = 0;
  const ObjectMotion* first_poses = nullptr;
  for (const ObjectMotion& m : motions) {
    if (m.kind == ObjectMotion::Kind::kKeyframes) {
      t0 = any_keyframes ? std::min(t0, m.keyframes.front().first) : m.keyframes.front().first;
      t1 = any_keyframes ? std::max(t1, m.keyframes.back().first) : m.keyframes.back().first;
      any_keyframes = true;
    } else if (m.kind == ObjectMotion::Kind::kPoses) {
      if (!first_poses) first_poses = &m;
      any_poses = true;
    } else {
      random_samples = std::max(random_samples, m.samples);
    }
  }
  // Skinned clips: one play from scene time 0, [0, duration / speed], in as many uniform samples as
  // the clip has distinct key times (at least 2).
  std::vector<double> skin_times;
  for (const SkinnedObject& k : skins) {
    if (!k.skeleton || k.clip < 0 || k.clip >= int(k.skeleton->clips.size())) continue;
    const SkinClip& clip = k.skeleton->clips[k.clip];
    const double span = clip.duration_s / k.speed;
    t0 = any_keyframes ? std::min(t0, 0.0) : 0.0;
    t1 = any_keyframes ? std::max(t1, span) : span;
    any_keyframes = true;
    const int n = std::max<int>(2, int(std::min<std::size_t>(clip.KeyTimes().size(), 100000)));
    for (int i = 0; i < n; ++i) skin_times.push_back(span * i / (n - 1));
  }
  // The axis: the study's, else inferred (pose names of the first motion with poses; else every
  // keyframe time and the skinned clips' times; else the random draws).
  std::vector<double> times;
  std::vector<std::string> pose_names;
  int count = 0;
  if (study.time && !study.time->poses.empty()) {
    pose_names = study.time->poses;
  } else if (study.time && !study.time->times.empty()) {
    times = study.time->times;
  } else if (study.time && study.time->samples > 0) {
    count = study.time->samples;
    if (any_keyframes)
      for (int i = 0; i < count; ++i)
        times.push_back(count == 1 ? t0 : t0 + (t1 - t0) * i / (count - 1));
  } else if (any_poses) {
    for (const auto& [name, pose] : first_poses->poses) pose_names.push_back(name);
  } else if (any_keyframes) {
    std::set<double> all(skin_times.begin(), skin_times.end());
    for (const ObjectMotion& m : motions)
      for (const auto& [t, pose] : m.keyframes) all.insert(t);
    times.assign(all.begin(), all.end());
  } else {
    count = random_samples;
  }
  const int n = !pose_names.empty() ? int(pose_names.size())
                : !times.empty()    ? int(times.size())
                                    : count;
  for (int i = 0; i < n; ++i) {
    TimeSample s;
    s.time = !times.empty() ? times[i] : double(i);
    s.timed = !times.empty();
    s.label = !pose_names.empty() ? "pose '" + pose_names[i] + "'"
              : !times.empty()    ? "t=" + SixDigits(times[i]) + " s"
                                  : "draw " + std::to_string(i + 1);
    for (const ObjectMotion& m : motions) {
      switch (m.kind) {
        case ObjectMotion::Kind::kKeyframes:
          s.poses.push_back(m.AtTime(s.time));
          break;
        case ObjectMotion::Kind::kPoses: {
          GroupPose p;
          for (const auto& [name, pose] : m.poses)
            if (!pose_names.empty() && name == pose_names[i]) p = pose;
          s.poses.push_back(p);
          break;
        }
        case ObjectMotion::Kind::kRandom:
          s.poses.push_back(m.RandomDraw(i));
          break;
      }
    }
    out.push_back(std::move(s));
  }
  return out;
}

int MotionOfObject(const Scene& scene, int object) {
  for (std::size_t k = 0; k < scene.motions.size(); ++k)
    for (int o : scene.motions[k].objects)
      if (o == object) return int(k);
  return -1;
}

std::vector<Vec3> ObjectVerticesAt(const Scene& scene, int object, const TimeSample& sample) {
  const SceneObject& o = scene.objects[object];
  std::vector<Vec3> v;
  if (o.skin >= 0 && o.skin < int(scene.skins.size()))
    v = scene.skins[o.skin].VerticesAt(sample.SkinTime());
  if (v.size() != o.mesh.vertices.size()) v = o.mesh.vertices;
  const int motion = MotionOfObject(scene, object);
  if (motion >= 0 && motion < int(sample.poses.size())) {
    const Eigen::Isometry3d T = MotionTransform(scene, motion, sample);
    for (Vec3& p : v) p = T * p;
  }
  return v;
}

Scene SceneAtSample(const Scene& scene, const TimeSample& sample) {
  Scene out = scene;
  for (const SkinnedObject& k : scene.skins) {
    std::vector<Vec3> v = k.VerticesAt(sample.SkinTime());
    if (v.size() == out.objects[k.object].mesh.vertices.size())
      out.objects[k.object].mesh.vertices = std::move(v);
  }
  for (SceneObject& o : out.objects) o.skin = -1;
  out.skins.clear();
  out.motions.clear();
  for (std::size_t k = 0; k < scene.motions.size() && k < sample.poses.size(); ++k) {
    const ObjectMotion& m = scene.motions[k];
    const Eigen::Isometry3d T = PoseTransform(sample.poses[k], m.anchor);
    for (int o : m.objects)
      for (Vec3& v : out.objects[o].mesh.vertices) v = T * v;
  }
  return out;
}

std::unique_ptr<RigidPartsRayCaster> MakeSceneParts(const Scene& scene) {
  const std::size_t rigid = scene.motions.size() + 1;
  std::vector<int> part_of(scene.objects.size(), 0);
  for (std::size_t k = 0; k < scene.motions.size(); ++k)
    for (int o : scene.motions[k].objects) part_of[o] = int(k) + 1;
  for (std::size_t j = 0; j < scene.skins.size(); ++j)
    part_of[scene.skins[j].object] = int(rigid + j);
  std::vector<TriangleMesh> parts(rigid + scene.skins.size());
  std::vector<std::vector<int>> index(parts.size());
  int next = 0;
  for (std::size_t o = 0; o < scene.objects.size(); ++o) {
    const TriangleMesh& mesh = scene.objects[o].mesh;
    const int k = part_of[o];
    parts[k].Append(mesh);
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) index[k].push_back(next + int(i));
    next += int(mesh.triangles.size());
  }
  std::vector<bool> deforms(parts.size(), false);
  for (std::size_t j = 0; j < scene.skins.size(); ++j) deforms[rigid + j] = true;
  return MakeEmbreeRigidParts(parts, index, deforms);
}

std::vector<Eigen::Isometry3d> PartTransforms(const Scene& scene, const TimeSample& sample) {
  const std::size_t rigid = scene.motions.size() + 1;
  std::vector<Eigen::Isometry3d> out(rigid + scene.skins.size(), Eigen::Isometry3d::Identity());
  for (std::size_t k = 0; k < scene.motions.size(); ++k)
    out[k + 1] = MotionTransform(scene, int(k), sample);
  for (std::size_t j = 0; j < scene.skins.size(); ++j)
    out[rigid + j] = MotionTransform(scene, MotionOfObject(scene, scene.skins[j].object), sample);
  return out;
}

std::vector<std::vector<Vec3>> PartVertices(const Scene& scene, const TimeSample& sample) {
  const std::size_t rigid = scene.motions.size() + 1;
  std::vector<std::vector<Vec3>> out(rigid + scene.skins.size());
  for (std::size_t j = 0; j < scene.skins.size(); ++j)
    out[rigid + j] = scene.skins[j].VerticesAt(sample.SkinTime());
  return out;
}

std::unique_ptr<RayCaster> CasterAtSample(const RigidPartsRayCaster& parts, const Scene& scene,
                                          const TimeSample& sample) {
  return parts.At(PartTransforms(scene, sample), PartVertices(scene, sample));
}

std::vector<TimeSample> SamplesOrAsPlaced(std::vector<TimeSample> samples) {
  if (samples.empty()) samples.push_back(TimeSample{"as placed", 0, {}, false});
  return samples;
}

Eigen::Isometry3d MotionTransform(const Scene& scene, int motion, const TimeSample& sample) {
  if (motion < 0 || motion >= int(scene.motions.size()) || motion >= int(sample.poses.size()))
    return Eigen::Isometry3d::Identity();
  return PoseTransform(sample.poses[motion], scene.motions[motion].anchor);
}

}  // namespace pandora
