// Models in the formats the Open Asset Import Library reads (PLY, STL,
// glTF/GLB, FBX, COLLADA, 3DS, ...), with CONTRACT's ids: object id = index of
// the mesh in the importer's list, facet id = running index of the face over
// those meshes. OBJ keeps its own strict reader (host/formats/obj/obj_loader.h).
// scenes/FORMAT.md has the rules (materials, node transforms, textures).
#pragma once

#include <string>

#include "scene/scene.h"

namespace opsila {

// True when the file's extension is one the importer reads, other than
// .obj (the strict OBJ reader's) and .json (scene files).
bool is_imported_model(const std::string& path);

// Loads a model file; texture maps are found relative to its folder, their
// images read as `images` says (add_texture_file). Like a bare OBJ it sets
// no camera or lights. Any importer failure is one InputError "FILE: problem";
// more than `max_triangles` is TooManyTriangles (core/errors.h).
Scene load_model(const std::string& path, MapImages images = MapImages::now,
                 std::size_t max_triangles = kMaxTriangles);

// The same from bytes in memory; `hint` is the format's extension (for
// example "ply"). Reads nothing from disk: any other file the importer asks
// for (a glTF's external buffer) holds `other`, absent when it is empty;
// texture maps named by path are ignored. This is what fuzzing wants.
Scene load_model_from_memory(const std::string& bytes, const std::string& name, const std::string& hint,
                             const std::string& other = "");

}  // namespace opsila
