// Reads FILE.fbx (the two-bone bar of tests/skinned_gltf.h after a round trip through Blender: glTF
// in, FBX out, in centimetres) with LoadSkinnedMeshFile and compares its "bend" clip with the
// closed form at clip times 0, 0.5 and 1 s: the vertices, scaled by 1/100, within 1e-5 m. (Between
// those keys Blender's exported curves interpolate quaternion components, not slerp: about 1 degree
// apart at 0.25 s, so only the key times and the midpoint, where both agree, are compared.)
#include <algorithm>
#include <cstdio>
#include <string>

#include "analysis/scene/mesh_io.h"
#include "analysis/util/error.h"
#include "tests/skinned_gltf.h"

int main(int argc, char** argv) {
  using namespace pandora;
  if (argc != 2) {
    std::fprintf(stderr, "usage: check_skinned_fbx FILE.fbx\n");
    return 2;
  }
  testing::SkinnedTube bar = testing::TwoBoneBar();
  bar.segments = 16;  // as make_skinned_bar writes it
  bar.Gltf();         // fills the generator's vertices
  try {
    const SkinnedMeshFile file = LoadSkinnedMeshFile(argv[1]);
    int clip = -1;
    for (std::size_t c = 0; c < file.skeleton->clips.size(); ++c)
      if (file.skeleton->clips[c].name.find("bend") != std::string::npos) clip = int(c);
    if (clip < 0 || file.parts.size() != 1) {
      std::printf("FAIL: no 'bend' clip or not one part: %s\n", file.skeleton->ClipList().c_str());
      return 1;
    }
    const SkinBinding& skin = *file.bindings[0];
    const std::vector<Vec3> start = skin.Skin(file.skeleton->Globals(clip, 0.0));
    // Each FBX vertex's generator vertex, by position at clip time 0.
    std::vector<std::size_t> match;
    for (const Vec3& p : start) {
      std::size_t best = 0;
      for (std::size_t k = 1; k < bar.vertices.size(); ++k)
        if ((bar.vertices[k] - p / 100).norm() < (bar.vertices[best] - p / 100).norm()) best = k;
      match.push_back(best);
    }
    double worst = 0;
    for (double tau : {0.0, 0.5, 1.0}) {
      const std::vector<Vec3> v = skin.Skin(file.skeleton->Globals(clip, tau));
      for (std::size_t i = 0; i < v.size(); ++i)
        worst = std::max(worst, (v[i] / 100 - bar.BendPose(match[i], tau)).norm());
    }
    if (!(worst < 1e-5) || start.size() < bar.vertices.size()) {
      std::printf("FAIL: the FBX bend clip is %.3g m from the closed form (%zu vertices)\n", worst,
                  start.size());
      return 1;
    }
    std::printf("ok: FBX through Blender, %zu vertices within %.2g m of the closed form\n",
                start.size(), worst);
  } catch (const InputError& e) {
    std::printf("FAIL: %s\n", e.what());
    return 1;
  }
  return 0;
}
