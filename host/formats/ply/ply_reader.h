// One rank's window of a PLY model read as a stream (docs/DISTRIBUTED.md,
// "One big model file"): the vertex element is read whole by every rank,
// the face element in bounded blocks, keeping only the faces of the
// window (ModelWindow: the rule is the OBJ stream's). The triangles are
// bit for bit those the importer path (model_import.cpp) makes of the
// file, with the same ids, materials and attributes.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "scene/scene.h"
#include "formats/common/window.h"

namespace opsila {

// Why the PLY stream does not read this file exactly as the importer does
// (other elements than 'vertex' then 'face', face properties other than
// one index list, a texture named in a comment, ...), "" when it does. The
// importer path reads the others whole, and judges a file or header the
// stream cannot read (the reason then says why).
std::string ply_stream_refusal(const std::string& path);

// True for a PLY with a 'tristrips' element: the importer keeps one
// triangle of its strips, so one process reads such a file with the stream
// too (load_ply_whole). Throws, naming the file and why, when the stream
// cannot read it; false for a header the stream cannot read at all (the
// importer path then judges it). `bytes`: the file in memory, if given.
bool ply_has_strips(const std::string& path, const std::string* bytes = nullptr);

// A text PLY the stream reads, read through once and checked as the ranks
// check it, keeping nothing, before one process hands it to the importer:
// the importer takes "0abc" as 0, 2.9 as an index 2 and ignores the rest
// of a line, which ranks refuse (one process must read what they read).
// Throws the stream's error; nothing for a binary file or one the stream
// leaves to the importer.
void check_ply_text(const std::string& path, std::size_t max_triangles, const std::string* bytes = nullptr);

// The whole file as one process reads it, by the stream (from `bytes`, if given).
Scene load_ply_whole(const std::string& path, std::size_t max_triangles, const std::string* bytes = nullptr);

// One warning for each element of a PLY read through the importer that
// gives no facets and is not the importer's 'material' (an 'edge', a
// 'range_grid', ...): a file declaring more faces than get drawn says so.
std::vector<std::string> ply_unread_elements(const std::string& path);

// As load_obj_window, for a PLY file the stream reads (ply_stream_refusal
// is ""): `fans` gets the file's fan triangles; 0 in window.fans keeps no
// face (the counting read).
Scene load_ply_window(const std::string& path, std::size_t max_triangles, const ModelWindow& window,
                      std::uint64_t& fans, std::size_t block_bytes = std::size_t(32) << 20);

}  // namespace opsila
