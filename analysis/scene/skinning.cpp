#include "analysis/scene/skinning.h"

#include <algorithm>
#include <cmath>
#include <set>

namespace pandora {
namespace {

// Index of the segment [k, k + 1] holding t and the weight of k + 1; keys sorted by time.
template <typename Key>
std::pair<std::size_t, double> Segment(const std::vector<Key>& keys, double t) {
  if (!(t > keys.front().first)) return {0, 0.0};
  if (!(t < keys.back().first)) return {keys.size() - 1, 0.0};
  const auto next = std::upper_bound(keys.begin(), keys.end(), t,
                                     [](double v, const Key& k) { return v < k.first; });
  const std::size_t k = std::size_t(next - keys.begin()) - 1;
  const double span = keys[k + 1].first - keys[k].first;
  return {k, span > 0 ? (t - keys[k].first) / span : 0.0};
}

Vec3 Lerp(const std::vector<std::pair<double, Vec3>>& keys, double t) {
  const auto [k, w] = Segment(keys, t);
  if (w == 0.0) return keys[k].second;
  return (1 - w) * keys[k].second + w * keys[k + 1].second;
}

Eigen::Quaterniond Slerp(const std::vector<std::pair<double, Eigen::Quaterniond>>& keys, double t) {
  const auto [k, w] = Segment(keys, t);
  if (w == 0.0) return keys[k].second;
  return keys[k].second.slerp(w, keys[k + 1].second);  // Eigen takes the shorter arc.
}

}  // namespace

std::vector<double> SkinClip::KeyTimes() const {
  std::set<double> all;
  for (const NodeChannel& c : channels) {
    for (const auto& k : c.position) all.insert(k.first);
    for (const auto& k : c.rotation) all.insert(k.first);
    for (const auto& k : c.scaling) all.insert(k.first);
  }
  return std::vector<double>(all.begin(), all.end());
}

std::vector<Eigen::Matrix4d> Skeleton::Globals(int clip, double t) const {
  std::vector<Eigen::Matrix4d> local(nodes.size());
  for (std::size_t i = 0; i < nodes.size(); ++i) local[i] = nodes[i].rest_local;
  if (clip >= 0 && clip < int(clips.size())) {
    for (const NodeChannel& c : clips[clip].channels) {
      if (c.node < 0 || c.node >= int(nodes.size())) continue;
      // The rest transform's parts for the kinds without keys (T * R * S, no shear).
      const Eigen::Matrix4d& rest = nodes[c.node].rest_local;
      const Mat3 m = rest.topLeftCorner<3, 3>();
      Vec3 scale(m.col(0).norm(), m.col(1).norm(), m.col(2).norm());
      Mat3 r = m;
      for (int j = 0; j < 3; ++j)
        if (scale[j] > 0) r.col(j) /= scale[j];
      Vec3 position = rest.topRightCorner<3, 1>();
      Eigen::Quaterniond rotation(r);
      if (!c.position.empty()) position = Lerp(c.position, t);
      if (!c.rotation.empty()) rotation = Slerp(c.rotation, t);
      if (!c.scaling.empty()) scale = Lerp(c.scaling, t);
      Eigen::Matrix4d L = Eigen::Matrix4d::Identity();
      L.topLeftCorner<3, 3>() = rotation.normalized().toRotationMatrix() * scale.asDiagonal();
      L.topRightCorner<3, 1>() = position;
      local[c.node] = L;
    }
  }
  std::vector<Eigen::Matrix4d> global(nodes.size());
  for (std::size_t i = 0; i < nodes.size(); ++i)
    global[i] =
        nodes[i].parent >= 0 ? Eigen::Matrix4d(global[nodes[i].parent] * local[i]) : local[i];
  return global;
}

std::string Skeleton::ClipList() const {
  std::string out;
  for (std::size_t i = 0; i < clips.size(); ++i) {
    if (!out.empty()) out += ", ";
    out += clips[i].name.empty() ? "unnamed" : "'" + clips[i].name + "'";
    out += " (" + std::to_string(i) + ")";
  }
  return out;
}

std::vector<Vec3> SkinBinding::Skin(const std::vector<Eigen::Matrix4d>& globals) const {
  std::vector<Eigen::Matrix4d> bone(bones.size());
  for (std::size_t b = 0; b < bones.size(); ++b)
    bone[b] = globals[bones[b].first] * bones[b].second;
  std::vector<Vec3> out(mesh_vertices.size());
  for (std::size_t v = 0; v < mesh_vertices.size(); ++v) {
    const Eigen::Vector4d x(mesh_vertices[v].x(), mesh_vertices[v].y(), mesh_vertices[v].z(), 1.0);
    Eigen::Vector4d sum = Eigen::Vector4d::Zero();
    for (int i = first[v]; i < first[v + 1]; ++i)
      sum += influences[i].second * (bone[influences[i].first] * x);
    out[v] = sum.head<3>();
  }
  return out;
}

double SkinnedObject::ClipTime(double t) const {
  const double duration = skeleton && clip >= 0 && clip < int(skeleton->clips.size())
                              ? skeleton->clips[clip].duration_s
                              : 0;
  const double c = offset_s + speed * t;
  if (!(duration > 0)) return 0;
  if (loop) {
    const double wrapped = std::fmod(c, duration);
    return wrapped < 0 ? wrapped + duration : wrapped;
  }
  return std::min(std::max(c, 0.0), duration);
}

std::vector<Vec3> SkinnedObject::VerticesAt(double t) const {
  if (!skeleton || !binding) return {};
  std::vector<Vec3> v = binding->Skin(skeleton->Globals(clip, ClipTime(t)));
  for (Vec3& p : v) p = world_from_file * p;
  return v;
}

std::vector<Vec3> SkinnedObject::RestVertices() const {
  if (!skeleton || !binding) return {};
  std::vector<Vec3> v = binding->Skin(skeleton->Globals(-1, 0));
  for (Vec3& p : v) p = world_from_file * p;
  return v;
}

}  // namespace pandora
