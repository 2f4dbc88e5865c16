// libFuzzer target: bytes -> the Open Asset Import Library -> SPEC's scene
// (load_model_from_memory). The first byte picks the format the importer is
// told to expect (STL, OFF or glTF); the conversion layer must turn whatever
// the importer accepts into a valid scene or one InputError. Nothing is read
// from disk. PLY is left out: the importer's own PLY header reader loops
// forever on some malformed headers (docs/RELIABILITY.md); PLY files are
// covered by the unit tests instead.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "core/scene.h"
#include "input/model_import.h"

namespace {

void require(bool ok) {
  if (!ok) std::abort();
}

void check(const opsila::Scene& s) {
  require(!s.triangles.empty() && !s.materials.empty());
  for (const opsila::Triangle& t : s.triangles) {
    require(t.facet_id >= 0 && t.facet_id < s.num_facets);
    require(t.object_id >= 0 && t.object_id < s.num_objects);
    require(t.material >= 0 && static_cast<std::size_t>(t.material) < s.materials.size());
    require(t.attributes < 0 || static_cast<std::size_t>(t.attributes) < s.attributes.size());
    for (const opsila::Vec3* v : {&t.v0, &t.v1, &t.v2})
      for (float x : *v) require(std::isfinite(x));
  }
  for (const opsila::MaterialDesc& m : s.materials) {
    require(m.map_kd < static_cast<int>(s.textures.size()));
    require(m.map_ka < static_cast<int>(s.textures.size()));
  }
  require(std::isfinite(s.epsilon()) && s.epsilon() > 0);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static const char* const kHints[] = {"stl", "off", "gltf"};
  const char* hint = kHints[data[0] % 3];
  const std::string bytes(reinterpret_cast<const char*>(data + 1), size - 1);
  try {
    check(opsila::load_model_from_memory(bytes, std::string("fuzz.") + hint, hint));
  } catch (const opsila::InputError&) {
  }
  return 0;
}
