// The importer's materials as CONTRACT's (CONTRACT "Materials", and "Geometry" on
// other model formats): which material is the importer's placeholder for
// "no material", which keys a material gives, and its texture maps.
#pragma once

#include <string>
#include <vector>

#include "scene/scene.h"

struct aiScene;

namespace opsila {

// Appends the importer's materials to scene.materials (their maps to
// scene.textures) and returns, for each of them, its index in
// scene.materials: 0, CONTRACT's default, for the importer's placeholder.
// Warnings start with `name`; map files are found from `base_dir` ("" when
// the model came from memory: no file is read then), their images read as
// `images` says (add_texture_file).
std::vector<int> import_materials(const aiScene& ai, const std::string& name, const std::string& base_dir,
                                  Scene& scene, MapImages images);

}  // namespace opsila
