// libFuzzer target for the viewer's script reader: bytes -> viewer::ParseScript (every action
// parsed and validated; nothing runs).
#include <cstdint>
#include <string>

#include "analysis/util/error.h"
#include "tests/fuzz/fuzz_targets.h"
#include "viewer/core/script.h"

namespace pandora::fuzz {

void ScriptTarget(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const std::vector<viewer::Action> actions = viewer::ParseScript(text, "fuzz.json");
  std::size_t ids = 0;
  for (const viewer::Action& a : actions) ids += a.cameras.size() + a.text.size() + a.text2.size();
  (void)ids;
}

}  // namespace pandora::fuzz

#ifndef PANDORA_FUZZ_NO_MAIN
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    pandora::fuzz::ScriptTarget(data, size);
  } catch (const pandora::InputError&) {
  }
  return 0;
}
#endif
