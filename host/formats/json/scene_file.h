// Scene input: the project's JSON scene format (scenes/FORMAT.md) or a bare
// Wavefront OBJ. All bad input is an InputError whose message names the file,
// the line and, for scene files, the key path (e.g. objects[3].material.Kd).
#pragma once

#include <cstddef>
#include <string>

#include "formats/obj/obj_loader.h"
#include "scene/scene.h"

namespace opsila {

// Largest JSON scene file (scenes/FORMAT.md "Limits"): scene files describe,
// models and generators make the geometry. Reading one costs a small
// multiple of its size.
constexpr std::size_t kMaxSceneFileBytes = std::size_t(4) << 20;

// ".obj" (any case) goes to load_obj; anything else is read as a JSON scene.
// With share.ranks > 1 a JSON scene or an OBJ is read as this rank's share
// (share.rank of share.ranks; Scene::share), and may have share.ranks times
// one rank's triangles; other model files are read whole. `limit` is one
// rank's triangles (prepare/prepare.h gives what its memory holds); more is
// refused before it is built, or as soon as a streamed file passes it.
Scene load_scene(const std::string& path, const SceneShare& share = SceneShare{},
                 const TriangleLimit& limit = TriangleLimit{});

// One rank's triangle limit: `limit`, or lower where the environment
// variable OPSILA_RANK_TRIANGLE_LIMIT says so (the tests' way to reach it
// with a small scene).
TriangleLimit rank_triangle_limit(const TriangleLimit& limit);

// A JSON scene from memory. `name` is the file name used in messages; OBJ
// files named by the scene are looked up relative to `base_dir`. With an
// empty base_dir the scene may not name other files (an "obj" object is an
// error), so fuzzed input never touches the disk. Scenes that would make
// more than `limit` triangles are refused before they are built.
Scene load_scene_from_string(const std::string& text, const std::string& name,
                             const std::string& base_dir,
                             const TriangleLimit& limit = TriangleLimit{},
                             const SceneShare& share = SceneShare{});

}  // namespace opsila
