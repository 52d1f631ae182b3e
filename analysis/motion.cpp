#include "analysis/motion.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "analysis/ray_caster.h"
#include "analysis/seeded.h"
#include "analysis/scene.h"

namespace pandora {
namespace {

constexpr double kPi = 3.14159265358979323846;


std::string Short(double v) {
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
  for (int k = 0; k < 3; ++k) at[k] = box.min[k] + SeededUniform(seed, std::uint64_t(i), std::uint64_t(k)) * (box.max[k] - box.min[k]);
  p.move = at - anchor;
  p.yaw_deg = yaw_min_deg + SeededUniform(seed, std::uint64_t(i), 3) * (yaw_max_deg - yaw_min_deg);
  return p;
}

std::vector<TimeSample> Scene::TimeSamples() const {
  std::vector<TimeSample> out;
  if (motions.empty()) return out;
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
  // The axis: the study's, else inferred (pose names of the first motion with poses; else every
  // keyframe time; else the random draws).
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
      for (int i = 0; i < count; ++i) times.push_back(count == 1 ? t0 : t0 + (t1 - t0) * i / (count - 1));
  } else if (any_poses) {
    for (const auto& [name, pose] : first_poses->poses) pose_names.push_back(name);
  } else if (any_keyframes) {
    std::set<double> all;
    for (const ObjectMotion& m : motions)
      for (const auto& [t, pose] : m.keyframes) all.insert(t);
    times.assign(all.begin(), all.end());
  } else {
    count = random_samples;
  }
  const int n = !pose_names.empty() ? int(pose_names.size()) : !times.empty() ? int(times.size()) : count;
  for (int i = 0; i < n; ++i) {
    TimeSample s;
    s.time = !times.empty() ? times[i] : double(i);
    s.label = !pose_names.empty() ? "pose '" + pose_names[i] + "'"
              : !times.empty()    ? "t=" + Short(times[i]) + " s"
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

Scene SceneAtSample(const Scene& scene, const TimeSample& sample) {
  Scene out = scene;
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
  std::vector<int> part_of(scene.objects.size(), 0);
  for (std::size_t k = 0; k < scene.motions.size(); ++k)
    for (int o : scene.motions[k].objects) part_of[o] = int(k) + 1;
  std::vector<TriangleMesh> parts(scene.motions.size() + 1);
  std::vector<std::vector<int>> index(parts.size());
  int next = 0;
  for (std::size_t o = 0; o < scene.objects.size(); ++o) {
    const TriangleMesh& mesh = scene.objects[o].mesh;
    const int k = part_of[o];
    parts[k].Append(mesh);
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) index[k].push_back(next + int(i));
    next += int(mesh.triangles.size());
  }
  return MakeEmbreeRigidParts(parts, index);
}

std::vector<Eigen::Isometry3d> PartTransforms(const Scene& scene, const TimeSample& sample) {
  std::vector<Eigen::Isometry3d> out(scene.motions.size() + 1, Eigen::Isometry3d::Identity());
  for (std::size_t k = 0; k < scene.motions.size(); ++k) out[k + 1] = MotionTransform(scene, int(k), sample);
  return out;
}

std::vector<TimeSample> SamplesOrAsPlaced(std::vector<TimeSample> samples) {
  if (samples.empty()) samples.push_back(TimeSample{"as placed", 0, {}});
  return samples;
}

Eigen::Isometry3d MotionTransform(const Scene& scene, int motion, const TimeSample& sample) {
  if (motion < 0 || motion >= int(scene.motions.size()) || motion >= int(sample.poses.size()))
    return Eigen::Isometry3d::Identity();
  return PoseTransform(sample.poses[motion], scene.motions[motion].anchor);
}

}  // namespace pandora
