// libFuzzer target for the scene loader: bytes -> ParseScene, parse and validate only.
#include <algorithm>
#include <cstdint>
#include <string>

#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "tests/fuzz/fuzz_targets.h"

#ifndef PANDORA_FUZZ_MESH_DIR
#error "define PANDORA_FUZZ_MESH_DIR, the folder of tests/fuzz/meshes"
#endif

namespace pandora::fuzz {

void SceneTarget(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const Scene scene = ParseScene(text, std::string(PANDORA_FUZZ_MESH_DIR) + "/fuzz.json");
  // Touch what a command would use next, without building a ray caster.
  for (const Rig& rig : scene.rigs) scene.FindRig(rig.name);
  scene.Bounds();
  scene.AllTriangles();
}

}  // namespace pandora::fuzz

#ifndef PANDORA_FUZZ_NO_MAIN
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    pandora::fuzz::SceneTarget(data, size);
  } catch (const pandora::InputError&) {
  }
  return 0;
}
#endif
