// libFuzzer target for the fields reader: bytes -> ReadFieldsVdbBytes -> CheckFieldsProvenance.
#include <cstdint>
#include <string>

#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "tests/fuzz/fuzz_targets.h"
#include "volume/fields.h"
#include "volume/vdb_io.h"

namespace pandora::fuzz {
namespace {

// tests/data/minimal.json, so the provenance check has a scene and a rig to compare with.
const Scene& MinimalScene() {
  static const Scene scene = ParseScene(R"({
  "pandora": 1,
  "objects": [{"name": "block", "box": {"size": [0.4, 0.4, 0.4]}, "position": [0, 0, 0.2], "solid": true}],
  "rigs": [{"name": "pair", "cameras": [
    {"id": "a", "position": [2, 0, 1], "look_at": [0, 0, 0.3], "resolution": [640, 480], "hfov_deg": 60},
    {"id": "b", "position": [0, 2, 1], "look_at": [0, 0, 0.3], "resolution": [640, 480], "hfov_deg": 60}]}],
  "study": {"region": {"box": {"min": [-0.5, -0.5, 0], "max": [0.5, 0.5, 0.6]}}, "voxel_size": 0.05}
})",
                                        "minimal.json");
  return scene;
}

}  // namespace

void FieldsTarget(const std::uint8_t* data, std::size_t size) {
  const Scene& scene = MinimalScene();
  FieldsProvenance provenance;
  const Fields fields = ReadFieldsVdbBytes(std::string(reinterpret_cast<const char*>(data), size),
                                           "fuzz.vdb", &provenance);
  CheckFieldsProvenance(provenance, fields.lattice, scene, scene.rigs[0], "fuzz.vdb");
}

}  // namespace pandora::fuzz

#ifndef PANDORA_FUZZ_NO_MAIN
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    pandora::fuzz::FieldsTarget(data, size);
  } catch (const pandora::InputError&) {
  }
  return 0;
}
#endif
