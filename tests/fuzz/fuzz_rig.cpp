// libFuzzer target for the calibrated-rig readers of `pandora import-rig`
// (analysis/rig/rig_formats.h): the first byte picks the reader (even: OpenCV YAML; odd: COLMAP,
// the rest split at the first
// "\n@images\n" into cameras.txt and images.txt). Every rig read must hold finite values only.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "analysis/rig/rig_formats.h"
#include "analysis/util/error.h"
#include "tests/fuzz/fuzz_targets.h"

namespace pandora::fuzz {

void RigTarget(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return;
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  Rig rig;
  if (data[0] % 2 == 0) {
    rig = ParseOpenCvYaml(text, "fuzz.yml");
  } else {
    const std::string marker = "\n@images\n";
    const std::size_t at = text.find(marker);
    const std::string cameras = at == std::string::npos ? text : text.substr(0, at);
    const std::string images =
        at == std::string::npos ? std::string() : text.substr(at + marker.size());
    rig = ParseColmap(cameras, "cameras.txt", images, "images.txt", "fuzz");
  }
  for (const Camera& c : rig.cameras) {
    const Intrinsics& k = c.model.intrinsics();
    for (double v : {k.fx, k.fy, k.cx, k.cy, k.k1, k.k2, k.p1, k.p2, k.k3, k.k4})
      if (!std::isfinite(v)) std::abort();
    if (!c.world_from_camera.matrix().allFinite() || k.width <= 0 || k.height <= 0) std::abort();
  }
}

}  // namespace pandora::fuzz

#ifndef PANDORA_FUZZ_NO_MAIN
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    pandora::fuzz::RigTarget(data, size);
  } catch (const pandora::InputError&) {
  }
  return 0;
}
#endif
