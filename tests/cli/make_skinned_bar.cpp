// Writes FOLDER/bar.gltf (the two-bone bar of tests/skinned_gltf.h) and FOLDER/scene.json: the bar
// 1 m above a floor playing its "bend" clip (the tip turns 90 degrees in 1 s), a ring of four
// cameras, the bar as a surface target, three time samples. For tests/cli/check_skin.sh.
#include <fstream>
#include <iostream>
#include <string>

#include "tests/skinned_gltf.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: make_skinned_bar FOLDER\n";
    return 2;
  }
  const std::string folder = argv[1];
  pandora::testing::SkinnedTube bar = pandora::testing::TwoBoneBar();
  bar.segments = 16;
  std::ofstream(folder + "/bar.gltf") << bar.Gltf();
  std::ofstream(folder + "/scene.json") << R"({"pandora": 1,
  "objects": [
    {"name": "bar", "mesh": {"file": "bar.gltf", "up_axis": "z"}, "position": [0, 0, 1],
     "animation": {"clip": "bend", "loop": false}},
    {"name": "floor", "plane": {"size": [6, 6]}}],
  "rigs": [{"name": "ring", "cameras": [
    {"id": "c0", "position": [3, 0, 2.5], "look_at": [1, 0.3, 0.8], "resolution": [640, 480], "hfov_deg": 60},
    {"id": "c1", "position": [1, 3, 2.5], "look_at": [1, 0.3, 0.8], "resolution": [640, 480], "hfov_deg": 60},
    {"id": "c2", "position": [-2, 0, 2.5], "look_at": [1, 0.3, 0.8], "resolution": [640, 480], "hfov_deg": 60},
    {"id": "c3", "position": [1, -3, 2.5], "look_at": [1, 0.3, 0.8], "resolution": [640, 480], "hfov_deg": 60}]}],
  "views": {"top": {"from": [1, 0.3, 5], "at": [1, 0.3, 0], "up": [0, 1, 0], "fov_deg": 60}},
  "study": {"region": {"box": {"min": [-0.5, -0.5, 0], "max": [2.5, 1.5, 1.5]}}, "voxel_size": 0.1,
            "time": {"times": [0, 0.5, 1], "min_cameras": 2}, "targets": {"objects": ["bar"], "points": 500}}
})";
  return 0;
}
