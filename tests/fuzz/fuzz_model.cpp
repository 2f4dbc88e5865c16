// libFuzzer target: bytes -> the Open Asset Import Library -> CONTRACT's scene
// (load_model_from_memory). The first byte picks the format the importer is
// told to expect (STL, OFF, glTF, GLB, PLY or FBX); bytes after the first
// "#EXTERNAL#" are every other file the importer opens (a glTF's external
// buffers), so crafted buffers take the path files on disk take. The checks
// before the importer (formats/assimp/model_checks.h) and the conversion layer must
// turn whatever the importer accepts into a valid scene or one InputError.
// Nothing is read from disk.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "scene/scene.h"
#include "formats/assimp/model_import.h"
#include "fuzz_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static const char* const kHints[] = {"stl", "off", "gltf", "glb", "ply", "fbx"};
  const char* hint = kHints[data[0] % 6];
  std::string bytes(reinterpret_cast<const char*>(data + 1), size - 1), other;
  const std::size_t cut = bytes.find("#EXTERNAL#");
  if (cut != std::string::npos) {
    other = bytes.substr(cut + 10);
    bytes.resize(cut);
  }
  try {
    fuzz::check_scene(opsila::load_model_from_memory(bytes, std::string("fuzz.") + hint, hint, other));
  } catch (const opsila::InputError&) {
  }
  return 0;
}
