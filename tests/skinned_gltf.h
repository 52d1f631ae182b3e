#pragma once
/// \file skinned_gltf.h
/// Writes small skinned glTF files for tests and benchmarks: a tube along +x (rings of `segments`
/// vertices, radius `radius`, closed by a fan at each end) on two bones, "bone0" at the origin and
/// its child "bone1" at (joint, 0, 0). Each ring's two raw weights are given (they need not sum to
/// 1: the loader normalises them). Two clips: "bend", bone1 turning about +z from 0 to 90 degrees
/// over 1 s, and "lift", bone0 moving from (0, 0, 0) to (0, 0, 1) over 2 s. Everything is exact in
/// float (positions, the 90-degree quaternion after normalisation), so poses have closed forms.

#include <cmath>
#include <cstdint>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "analysis/geometry/geometry.h"
#include "analysis/util/units.h"

namespace pandora::testing {

struct TubeRing {
  double x = 0;
  double w0 = 1, w1 = 0;  ///< Raw weights of bone0 and bone1.
};

struct SkinnedTube {
  std::vector<TubeRing> rings;
  int segments = 4;
  double radius = 0.1;
  double joint = 1.0;
  // Filled by Write: every vertex with its raw weights, as written (file coordinates).
  std::vector<Vec3> vertices;
  std::vector<std::pair<double, double>> weights;
  std::size_t triangles = 0;

  /// The glTF text (buffer embedded as base64).
  std::string Gltf();

  /// The closed-form position of vertex `v` in the "bend" clip at clip time tau in [0, 1]: the
  /// normalised blend of the rest position (bone0) and its turn by 90 tau degrees about the joint.
  Vec3 BendPose(std::size_t v, double tau) const {
    const double a = 0.5 * kPi * tau;
    const Vec3 p = vertices[v], j(joint, 0, 0);
    const Vec3 d = p - j;
    const Vec3 turned = j + Vec3(std::cos(a) * d.x() - std::sin(a) * d.y(),
                                 std::sin(a) * d.x() + std::cos(a) * d.y(), d.z());
    const double s = weights[v].first + weights[v].second;
    return (weights[v].first * p + weights[v].second * turned) / s;
  }
  /// The "lift" clip at clip time tau in [0, 2]: everything rises by tau / 2.
  Vec3 LiftPose(std::size_t v, double tau) const { return vertices[v] + Vec3(0, 0, tau / 2); }
};

namespace detail {
// `v` rounded to float, as the file stores it.
inline double Float(double v) {
  volatile float f = static_cast<float>(v);  // volatile: GCC 12 -O2 dropped the rounding here
  return static_cast<double>(f);
}
inline std::string Base64(const std::string& bytes) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const std::uint32_t n = (std::uint8_t(bytes[i]) << 16) | (std::uint8_t(bytes[i + 1]) << 8) |
                            std::uint8_t(bytes[i + 2]);
    for (int s = 18; s >= 0; s -= 6) out += k[(n >> s) & 63];
  }
  if (i + 1 == bytes.size()) {
    const std::uint32_t n = std::uint8_t(bytes[i]) << 16;
    out += k[(n >> 18) & 63];
    out += k[(n >> 12) & 63];
    out += "==";
  } else if (i + 2 == bytes.size()) {
    const std::uint32_t n = (std::uint8_t(bytes[i]) << 16) | (std::uint8_t(bytes[i + 1]) << 8);
    out += k[(n >> 18) & 63];
    out += k[(n >> 12) & 63];
    out += k[(n >> 6) & 63];
    out += '=';
  }
  return out;
}
template <typename T>
void Put(std::string* b, T v) {
  char c[sizeof(T)];
  std::memcpy(c, &v, sizeof(T));
  b->append(c, sizeof(T));
}
}  // namespace detail

inline std::string SkinnedTube::Gltf() {
  using detail::Float;
  using nlohmann::json;
  vertices.clear();
  weights.clear();
  std::vector<std::uint32_t> index;
  for (const TubeRing& r : rings)
    for (int s = 0; s < segments; ++s) {
      const double a = 2 * kPi * s / segments;
      // Rounded to float here so the closed forms use what the file holds.
      vertices.push_back(
          Vec3(Float(r.x), Float(radius * std::cos(a)), Float(radius * std::sin(a))));
      weights.emplace_back(r.w0, r.w1);
    }
  const std::uint32_t n = std::uint32_t(segments);
  for (std::uint32_t k = 0; k + 1 < rings.size(); ++k)
    for (std::uint32_t s = 0; s < n; ++s) {
      const std::uint32_t a = k * n + s, b = k * n + (s + 1) % n, c = a + n, d = b + n;
      index.insert(index.end(), {a, b, d, a, d, c});
    }
  // Caps: a centre vertex per end, triangles facing outward (-x at the first ring, +x at the last).
  const std::uint32_t c0 = std::uint32_t(vertices.size());
  vertices.push_back(Vec3(Float(rings.front().x), 0, 0));
  weights.emplace_back(rings.front().w0, rings.front().w1);
  const std::uint32_t c1 = std::uint32_t(vertices.size());
  vertices.push_back(Vec3(Float(rings.back().x), 0, 0));
  weights.emplace_back(rings.back().w0, rings.back().w1);
  const std::uint32_t last = std::uint32_t(rings.size() - 1) * n;
  for (std::uint32_t s = 0; s < n; ++s) {
    index.insert(index.end(), {c0, (s + 1) % n, s});
    index.insert(index.end(), {c1, last + s, last + (s + 1) % n});
  }
  triangles = index.size() / 3;

  std::string buf;
  json views = json::array(), accessors = json::array();
  auto view = [&](std::size_t start, int target) {
    while (buf.size() % 4) buf.push_back('\0');
    json v = {{"buffer", 0}, {"byteOffset", start}, {"byteLength", buf.size() - start}};
    if (target) v["target"] = target;
    views.push_back(v);
    return int(views.size()) - 1;
  };
  auto accessor = [&](int v, int type, std::size_t count, const char* kind,
                      json extra = json::object()) {
    json a = {{"bufferView", v}, {"componentType", type}, {"count", count}, {"type", kind}};
    a.update(extra);
    accessors.push_back(a);
    return int(accessors.size()) - 1;
  };
  // Positions.
  std::size_t start = buf.size();
  Vec3 lo = vertices[0], hi = vertices[0];
  for (const Vec3& p : vertices) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
    for (int k = 0; k < 3; ++k) detail::Put(&buf, float(p[k]));
  }
  const int pos = accessor(view(start, 34962), 5126, vertices.size(), "VEC3",
                           {{"min", {float(lo.x()), float(lo.y()), float(lo.z())}},
                            {"max", {float(hi.x()), float(hi.y()), float(hi.z())}}});
  start = buf.size();
  for (std::size_t v = 0; v < vertices.size(); ++v)
    for (std::uint16_t j : {0, 1, 0, 0}) detail::Put(&buf, j);
  const int joints = accessor(view(start, 34962), 5123, vertices.size(), "VEC4");
  start = buf.size();
  for (const auto& [w0, w1] : weights)
    for (float w : {float(w0), float(w1), 0.0f, 0.0f}) detail::Put(&buf, w);
  const int wts = accessor(view(start, 34962), 5126, vertices.size(), "VEC4");
  start = buf.size();
  for (std::uint32_t i : index) detail::Put(&buf, i);
  const int idx = accessor(view(start, 34963), 5125, index.size(), "SCALAR");
  // Inverse bind matrices (column major): bone0 the identity, bone1 a shift by -joint along x.
  start = buf.size();
  for (int b = 0; b < 2; ++b)
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r)
        detail::Put(&buf, float(r == c ? 1.0 : (b == 1 && c == 3 && r == 0) ? -joint : 0.0));
  const int ibm = accessor(view(start, 0), 5126, 2, "MAT4");
  // Clips.
  start = buf.size();
  for (float t : {0.0f, 1.0f}) detail::Put(&buf, t);
  const int bend_t = accessor(view(start, 0), 5126, 2, "SCALAR", {{"min", {0.0}}, {"max", {1.0}}});
  start = buf.size();
  const float h = float(std::sqrt(0.5));
  for (float q : {0.0f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f, h, h}) detail::Put(&buf, q);
  const int bend_q = accessor(view(start, 0), 5126, 2, "VEC4");
  start = buf.size();
  for (float t : {0.0f, 2.0f}) detail::Put(&buf, t);
  const int lift_t = accessor(view(start, 0), 5126, 2, "SCALAR", {{"min", {0.0}}, {"max", {2.0}}});
  start = buf.size();
  for (float v : {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 1.0f}) detail::Put(&buf, v);
  const int lift_v = accessor(view(start, 0), 5126, 2, "VEC3");

  json g = {
      {"asset", {{"version", "2.0"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0, 1}}}}},
      {"nodes",
       {{{"name", "tube"}, {"mesh", 0}, {"skin", 0}},
        {{"name", "bone0"}, {"children", {2}}},
        {{"name", "bone1"}, {"translation", {joint, 0.0, 0.0}}}}},
      {"meshes",
       {{{"name", "tube"},
         {"primitives",
          {{{"attributes", {{"POSITION", pos}, {"JOINTS_0", joints}, {"WEIGHTS_0", wts}}},
            {"indices", idx}}}}}}},
      {"skins", {{{"joints", {1, 2}}, {"inverseBindMatrices", ibm}, {"skeleton", 1}}}},
      {"animations",
       {{{"name", "bend"},
         {"samplers", {{{"input", bend_t}, {"output", bend_q}, {"interpolation", "LINEAR"}}}},
         {"channels", {{{"sampler", 0}, {"target", {{"node", 2}, {"path", "rotation"}}}}}}},
        {{"name", "lift"},
         {"samplers", {{{"input", lift_t}, {"output", lift_v}, {"interpolation", "LINEAR"}}}},
         {"channels", {{{"sampler", 0}, {"target", {{"node", 1}, {"path", "translation"}}}}}}}}},
      {"buffers",
       {{{"byteLength", buf.size()},
         {"uri", "data:application/octet-stream;base64," + detail::Base64(buf)}}}},
      {"bufferViews", views},
      {"accessors", accessors}};
  return g.dump(1);
}

/// The two-bone bar of the tests: rings at x = 0, 0.9 (bone0), 1.0 (raw weights 0.3 and 0.3:
/// normalised to a half each), 1.1 and 2 (bone1); a square tube (4 segments) of radius 0.1.
inline SkinnedTube TwoBoneBar() {
  SkinnedTube t;
  t.rings = {{0.0, 1, 0}, {0.9, 1, 0}, {1.0, 0.3, 0.3}, {1.1, 0, 1}, {2.0, 0, 1}};
  return t;
}

}  // namespace pandora::testing
