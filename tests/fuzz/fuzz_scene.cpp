// libFuzzer target for the scene loader: bytes -> ParseScene, parse and validate only.
#include <algorithm>
#include <cstdint>
#include <string>

#include "analysis/error.h"
#include "analysis/scene.h"
#include "tests/fuzz/fuzz_targets.h"

#ifndef PANDORA_FUZZ_MESH_DIR
#error "define PANDORA_FUZZ_MESH_DIR, the folder of tests/fuzz/meshes"
#endif

namespace pandora::fuzz {

bool SkipKnownSceneIssue(const std::uint8_t* data, std::size_t size) {
  // Nesting depth outside strings (the lead is bounding it in the loader).
  int depth = 0, deepest = 0;
  bool in_string = false, escaped = false;
  for (std::size_t i = 0; i < size; ++i) {
    const char c = char(data[i]);
    if (in_string) {
      if (escaped)
        escaped = false;
      else if (c == '\\')
        escaped = true;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      deepest = std::max(deepest, ++depth);
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  if (deepest > 64) return true;
  // DirectX .x meshes (a known assimp problem, being fixed in mesh_io).
  const std::string text(reinterpret_cast<const char*>(data), size);
  for (std::size_t at = text.find(".x"); at != std::string::npos; at = text.find(".x", at + 1)) {
    const std::size_t end = at + 2;
    if (end >= text.size() || text[end] == '"' || text[end] == '\\') return true;
  }
  for (std::size_t at = text.find(".X"); at != std::string::npos; at = text.find(".X", at + 1)) {
    const std::size_t end = at + 2;
    if (end >= text.size() || text[end] == '"' || text[end] == '\\') return true;
  }
  return false;
}

void SceneTarget(const std::uint8_t* data, std::size_t size) {
  if (SkipKnownSceneIssue(data, size)) return;
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
