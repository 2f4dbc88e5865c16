// libFuzzer target: scene JSON text -> load_scene_from_string, with no base
// folder (so "obj" objects are refused and nothing is read from disk) and a
// small triangle budget (so one input cannot take seconds or gigabytes).
// Only InputError is an acceptable refusal; anything else crashes.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "scene/scene.h"
#include "formats/json/scene_file.h"
#include "fuzz_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    fuzz::check_scene(opsila::load_scene_from_string(text, "fuzz.json", "", std::size_t(1) << 18));
  } catch (const opsila::InputError&) {
  }
  return 0;
}
