// Wavefront OBJ + MTL input with SPEC.md's facet/object id rules.
// The exact rules (ids, sections, materials, what is an error and what is a
// warning) are written down in scenes/FORMAT.md.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "core/scene.h"

namespace opsila {

// Upper bound on the triangles of one scene, all objects together (scenes/
// FORMAT.md "Limits"). The whole pipeline (load, partition, bank BVHs,
// device buffers) needs about 300 bytes per triangle on a CPU device, so
// 2^24 triangles fit a 24 GB machine with room to spare; beyond it the input
// is refused before it is built.
constexpr std::size_t kMaxTriangles = std::size_t(1) << 24;
// Upper bound on the size of any input file read by the loaders.
constexpr std::size_t kMaxInputFileBytes = std::size_t(1) << 31;

// Called on each chunk of a file as it is read (bytes, count, offset of the
// first byte); throws InputError to refuse the file there.
using ChunkCheck = std::function<void(const char*, std::size_t, std::size_t)>;

// Reads a whole regular file of at most max_bytes, a chunk at a time, each
// chunk checked before the next is read. Directories, devices, unreadable or
// oversized files give an InputError naming the path.
std::string read_input_file(const std::string& path, std::size_t max_bytes,
                            const ChunkCheck& check);
// Any file (an image) of at most kMaxInputFileBytes.
std::string read_input_file(const std::string& path);
// A text file (OBJ, MTL) of at most kMaxInputFileBytes: a NUL byte (a binary
// file) is refused as soon as it is read, not after gigabytes.
std::string read_text_file(const std::string& path);

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

// Parses MTL text (`name` for messages). Materials come back in definition
// order; a key a material leaves out keeps the SPEC default (colours 0,
// Ns = Ni = 1, illum 0). Soft problems are appended to `warnings`.
std::vector<MaterialDesc> parse_mtl(const std::string& text, const std::string& name,
                                    std::vector<std::string>& warnings);

}  // namespace opsila
