// Wavefront OBJ + MTL input with docs/CONTRACT.md's facet/object id rules.
// The exact rules (ids, sections, materials, what is an error and what is a
// warning) are written down in scenes/FORMAT.md.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/input_file.h"
#include "scene/scene.h"
#include "formats/common/window.h"

namespace opsila {

// Loads an OBJ file; its mtllib files are looked up in the OBJ's folder.
// Sets has_camera = has_lights = false; the camera frames the model. More
// than max_triangles triangles are refused as soon as they are counted.
// Throws InputError("FILE:LINE: problem") for malformed input.
Scene load_obj(const std::string& path, std::size_t max_triangles = kMaxTriangles);

// Same, from memory. `name` is the file name used in messages; mtllib files
// are looked up in `base_dir`. With an empty base_dir no file is read at all
// (mtllib lines are ignored with a warning), which is what fuzzing wants.
Scene load_obj_from_string(const std::string& text, const std::string& name,
                           const std::string& base_dir);

// How OBJ text is split to be parsed on several threads (the result never
// depends on it: the chunks are merged in file order, and a file with an
// error is read again whole, for its exact message). Tests force small chunks.
struct ObjChunking {
  std::size_t chunk_bytes = 0;  // 0: from the text's size and the threads (at least 1 MiB)
  int threads = 0;              // 0: core/parallel.h's host_threads()
};
Scene load_obj_from_string(const std::string& text, const std::string& name, const std::string& base_dir,
                           const ObjChunking& chunking, std::size_t max_triangles = kMaxTriangles);

// How an OBJ is streamed: blocks of about block_bytes, cut at line ends,
// each parsed in chunks. Tests force both small.
struct ObjStreaming {
  std::size_t block_bytes = std::size_t(32) << 20;
  ObjChunking chunking;
};
// Reads an OBJ as a stream, keeping every v, vt and vn (small next to the
// facets) but only the window's polygons. Every statement is parsed, so
// ids, counts, warnings and errors are one process's. The scene holds the
// window's triangles with the whole file's facet and object ids; its share
// (rank, ranks) has the whole file's triangle count and bounds (every rank
// sees every polygon, so no message is needed) and the objects whose
// triangles lie in several windows (spread). `fans` gets the file's fan
// triangles.
Scene load_obj_window(const std::string& path, std::size_t max_triangles, const ModelWindow& window,
                      std::uint64_t& fans, const ObjStreaming& streaming = ObjStreaming{});

// Parses MTL text (`name` for messages). Materials come back in definition
// order; a key a material leaves out keeps the CONTRACT default (colours 0,
// Ns = Ni = 1, illum 0). Soft problems are appended to `warnings`.
std::vector<MaterialDesc> parse_mtl(const std::string& text, const std::string& name,
                                    std::vector<std::string>& warnings);

}  // namespace opsila
