// libFuzzer target: OBJ text -> load_obj_from_string. Only InputError is an
// acceptable way to refuse input; anything else (another exception, a
// sanitizer report, a broken invariant) crashes and is reported.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "formats/obj/obj_loader.h"
#include "fuzz_checks.h"
#include "scene/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    // No base folder: mtllib lines never touch the disk.
    fuzz::check_scene(opsila::load_obj_from_string(text, "fuzz.obj", ""));
  } catch (const opsila::InputError&) {
  }
  return 0;
}
