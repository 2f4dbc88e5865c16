// Wavefront OBJ + MTL input with SPEC.md's facet/object id rules.
// The exact rules (ids, sections, materials, what is an error and what is a
// warning) are written down in scenes/FORMAT.md.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "core/scene.h"

namespace opsila {

// Upper bound on the triangles one load may produce (about 6 GiB of
// triangles); beyond it the input is refused rather than exhausting memory.
constexpr std::size_t kMaxTriangles = std::size_t(1) << 27;
// Upper bound on the size of any input file read by the loaders.
constexpr std::size_t kMaxInputFileBytes = std::size_t(1) << 31;

// Reads a whole regular file. Directories, devices, unreadable or oversized
// files give an InputError naming the path.
std::string read_input_file(const std::string& path);

// Loads an OBJ file; its mtllib files are looked up in the OBJ's folder.
// Sets has_camera = has_lights = false; the camera frames the model.
// Throws InputError("FILE:LINE: problem") for malformed input.
Scene load_obj(const std::string& path);

// Same, from memory. `name` is the file name used in messages; mtllib files
// are looked up in `base_dir`. With an empty base_dir no file is read at all
// (mtllib lines are ignored with a warning), which is what fuzzing wants.
Scene load_obj_from_string(const std::string& text, const std::string& name,
                           const std::string& base_dir);

// Parses MTL text (`name` for messages). Materials come back in definition
// order; a key a material leaves out keeps the SPEC default (colours 0,
// Ns = Ni = 1, illum 0). Soft problems are appended to `warnings`.
std::vector<MaterialDesc> parse_mtl(const std::string& text, const std::string& name,
                                    std::vector<std::string>& warnings);

}  // namespace opsila
