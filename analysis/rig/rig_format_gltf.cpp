// The scene and a rig as glTF 2 (.gltf / .glb; analysis/rig/rig_formats.h, docs/tool-chain.md).
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "analysis/geometry/pose.h"
#include "analysis/rig/rig_format_text.h"
#include "analysis/rig/rig_formats.h"
#include "analysis/util/color.h"
#include "analysis/util/error.h"
#include "analysis/util/text.h"
#include "analysis/util/units.h"

namespace pandora {

using namespace rig_format;  // NOLINT: the formats' shared helpers

namespace {

template <class T>
void Append(std::string& buffer, T value) {
  buffer.append(reinterpret_cast<const char*>(&value), sizeof value);
}

// Pandora world (Z up) to glTF (Y up).
Mat3 GltfFromWorld() {
  Mat3 c;
  c << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  return c;
}

}  // namespace

std::string SceneToGltf(const Scene& scene, const Rig& rig, bool binary) {
  const Mat3 c = GltfFromWorld();
  std::string buffer;
  json accessors = json::array(), views = json::array(), meshes = json::array(),
       materials = json::array(), nodes = json::array(), cameras = json::array();
  std::map<int, int> material_index;
  const auto material_of = [&](int m) {
    auto it = material_index.find(m);
    if (it != material_index.end()) return it->second;
    const Vec3 colour =
        m >= 0 ? scene.materials[static_cast<std::size_t>(m)].color : Vec3(0.7, 0.7, 0.7);
    materials.push_back(
        {{"name", m >= 0 ? scene.materials[static_cast<std::size_t>(m)].name : "default"},
         {"pbrMetallicRoughness",
          {{"baseColorFactor", {colour.x(), colour.y(), colour.z(), 1.0}},
           {"metallicFactor", 0.0},
           {"roughnessFactor", 1.0}}}});
    const int index = static_cast<int>(materials.size()) - 1;
    material_index[m] = index;
    return index;
  };
  for (const SceneObject& object : scene.objects) {
    if (object.mesh.triangles.empty()) continue;
    // Positions (float, glTF frame), then indices (uint32); each view 4-byte aligned.
    const std::size_t position_offset = buffer.size();
    Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
    Eigen::Vector3f hi = -lo;
    for (const Vec3& v : object.mesh.vertices) {
      const Eigen::Vector3f p = (c * v).cast<float>();
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
      Append(buffer, p.x()), Append(buffer, p.y()), Append(buffer, p.z());
    }
    const std::size_t index_offset = buffer.size();
    for (const Eigen::Vector3i& t : object.mesh.triangles)
      for (int j = 0; j < 3; ++j) Append(buffer, static_cast<std::uint32_t>(t[j]));
    const int view = static_cast<int>(views.size());
    views.push_back({{"buffer", 0},
                     {"byteOffset", position_offset},
                     {"byteLength", index_offset - position_offset},
                     {"target", 34962}});
    views.push_back({{"buffer", 0},
                     {"byteOffset", index_offset},
                     {"byteLength", buffer.size() - index_offset},
                     {"target", 34963}});
    const int accessor = static_cast<int>(accessors.size());
    accessors.push_back({{"bufferView", view},
                         {"componentType", 5126},
                         {"count", object.mesh.vertices.size()},
                         {"type", "VEC3"},
                         {"min", {lo.x(), lo.y(), lo.z()}},
                         {"max", {hi.x(), hi.y(), hi.z()}}});
    accessors.push_back({{"bufferView", view + 1},
                         {"componentType", 5125},
                         {"count", object.mesh.triangles.size() * 3},
                         {"type", "SCALAR"}});
    meshes.push_back({{"name", object.name},
                      {"primitives",
                       {{{"attributes", {{"POSITION", accessor}}},
                         {"indices", accessor + 1},
                         {"material", material_of(object.material)}}}}});
    nodes.push_back({{"name", object.name}, {"mesh", meshes.size() - 1}});
  }
  Mat3 flip = Mat3::Identity();
  flip(1, 1) = flip(2, 2) =
      -1;  // OpenCV camera (y down, z forward) -> glTF camera (y up, -z forward)
  for (const Camera& camera : rig.cameras) {
    const Intrinsics& k = camera.model.intrinsics();
    json perspective = {{"yfov", 2.0 * std::atan(0.5 * k.height / k.fy)},
                        {"aspectRatio", (double(k.width) * k.fy) / (double(k.height) * k.fx)},
                        {"znear", camera.near > 0 ? camera.near : 0.01}};
    if (std::isfinite(camera.far)) perspective["zfar"] = camera.far;
    cameras.push_back({{"name", camera.id}, {"type", "perspective"}, {"perspective", perspective}});
    const Mat3 r = c * camera.world_from_camera.linear() * flip;
    Eigen::Quaterniond q(r);
    q.normalize();
    const Vec3 p = c * camera.center();
    nodes.push_back({{"name", camera.id},
                     {"camera", cameras.size() - 1},
                     {"translation", {p.x(), p.y(), p.z()}},
                     {"rotation", {q.x(), q.y(), q.z(), q.w()}}});
  }
  json scene_nodes = json::array();
  for (std::size_t i = 0; i < nodes.size(); ++i) scene_nodes.push_back(i);
  json doc = {{"asset", {{"version", "2.0"}, {"generator", "pandora export-rig"}}},
              {"scene", 0},
              {"scenes", {{{"name", scene.path}, {"nodes", scene_nodes}}}},
              {"nodes", nodes}};
  if (!cameras.empty()) doc["cameras"] = cameras;
  if (!meshes.empty()) {
    doc["meshes"] = meshes;
    doc["materials"] = materials;
    doc["accessors"] = accessors;
    doc["bufferViews"] = views;
    doc["buffers"] = {{{"byteLength", buffer.size()}}};
    if (!binary)
      doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + Base64(buffer);
  }
  if (!binary) return doc.dump(1) + "\n";
  // GLB: a 12-byte header, a JSON chunk padded with spaces and a BIN chunk padded with zeros, each
  // a multiple of 4 bytes (glTF 2.0, "Binary glTF Layout").
  std::string text = doc.dump();
  while (text.size() % 4) text += ' ';
  while (buffer.size() % 4) buffer += '\0';
  std::string glb;
  const bool has_bin = !meshes.empty();
  const std::uint32_t total =
      static_cast<std::uint32_t>(12 + 8 + text.size() + (has_bin ? 8 + buffer.size() : 0));
  Append(glb, std::uint32_t{0x46546C67});  // "glTF"
  Append(glb, std::uint32_t{2});
  Append(glb, total);
  Append(glb, static_cast<std::uint32_t>(text.size()));
  Append(glb, std::uint32_t{0x4E4F534A});  // "JSON"
  glb += text;
  if (has_bin) {
    Append(glb, static_cast<std::uint32_t>(buffer.size()));
    Append(glb, std::uint32_t{0x004E4942});  // "BIN\0"
    glb += buffer;
  }
  return glb;
}

}  // namespace pandora
