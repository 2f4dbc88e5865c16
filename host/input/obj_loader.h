// Wavefront OBJ + MTL input with SPEC.md's facet/object id rules.
// The exact rules (ids, sections, materials, what is an error and what is a
// warning) are written down in scenes/FORMAT.md.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/input_file.h"
#include "core/scene.h"

namespace opsila {

// Upper bound on the triangles of one scene, all objects together (scenes/
// FORMAT.md "Limits"). The whole pipeline (load, partition, bank BVHs,
// device buffers) needs about 300 bytes per triangle on a CPU device, so
// 2^24 triangles fit a 24 GB machine with room to spare; beyond it the input
// is refused before it is built.
constexpr std::size_t kMaxTriangles = std::size_t(1) << 24;

// Any file (an image) of at most kMaxInputFileBytes.
std::string read_input_file(const std::string& path);
// A text file (OBJ, MTL) of at most kMaxInputFileBytes: a NUL byte (a binary
// file) is refused as soon as it is read, not after gigabytes.
std::string read_text_file(const std::string& path);
// That check, for a file read in chunks: UTF-16 and NUL bytes, by line.
ChunkCheck text_check(const std::string& path);

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

// One rank's window of an OBJ read as a stream (docs/DISTRIBUTED.md): the
// file's fan triangles take [plan_begin, plan_begin + plan_all) of a plan
// of plan_total triangles dealt over `ranks` in equal slices, and this rank
// keeps the polygons whose first fan triangle falls in its slice (a polygon
// is never cut). fans: the file's fan triangles, counted by a first read; 0
// keeps no polygon (that first read: counts, materials, warnings, errors).
struct ObjWindow {
  int rank = 0, ranks = 1;
  std::uint64_t plan_begin = 0, plan_all = 0, plan_total = 0;
  std::uint64_t fans = 0;
  bool load_maps = true;  // the materials' texture maps (the read that keeps the materials)
};
// The rank whose slice of the plan holds the file's fan triangle `fan`
// (-1 when the window keeps nothing: the counting read). The PLY stream's
// rule too.
int window_owner(const ObjWindow& plan, std::uint64_t fan);
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
Scene load_obj_window(const std::string& path, std::size_t max_triangles, const ObjWindow& window,
                      std::uint64_t& fans, const ObjStreaming& streaming = ObjStreaming{});

// Parses MTL text (`name` for messages). Materials come back in definition
// order; a key a material leaves out keeps the SPEC default (colours 0,
// Ns = Ni = 1, illum 0). Soft problems are appended to `warnings`.
std::vector<MaterialDesc> parse_mtl(const std::string& text, const std::string& name,
                                    std::vector<std::string>& warnings);

}  // namespace opsila
