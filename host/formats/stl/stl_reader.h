// One rank's window of a binary STL model read as a stream
// (docs/DISTRIBUTED.md, "One big model file"): the 50-byte facet records
// are read in blocks, keeping only the window's (ModelWindow). The
// triangles are bit for bit those the importer path (model_import.cpp)
// makes of the file.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "formats/common/window.h"
#include "scene/scene.h"

namespace opsila {

// Why the STL stream does not read this file exactly as the importer does,
// "" when it does (stl::stream_refusal, stl_format.h), or that the file
// cannot be read (the importer path then judges it, with its own message).
std::string stl_stream_refusal(const std::string& path);

// As load_ply_window, for a binary STL the stream reads: the 50-byte
// records are read in blocks of about block_bytes (a record at least, 64 Ki
// records at most).
Scene load_stl_window(const std::string& path, std::size_t max_triangles, const ModelWindow& window,
                      std::uint64_t& fans, std::size_t block_bytes = std::size_t(32) << 20);

}  // namespace opsila
