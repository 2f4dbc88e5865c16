// The model files other than OBJ that several ranks read as a stream, each
// keeping its window of the faces (docs/DISTRIBUTED.md, "One big PLY file",
// "One big STL file"): a PLY (ply_window.cpp) and a binary STL
// (stl_window.cpp), each only when the stream reads it exactly as the
// importer path (model_import.cpp) does; the others are read whole.
#pragma once

#include <cstdint>
#include <string>

#include "scene/scene.h"
#include "formats/common/window.h"

namespace opsila {

// True for the extensions a stream reads (.ply, .stl, any case).
bool is_streamed_model(const std::string& path);

// Why the stream of the file's format does not read it exactly as the
// importer does, "" when it does (ply_stream_refusal, stl_stream_refusal).
std::string model_stream_refusal(const std::string& path);

// As load_obj_window, for a file model_stream_refusal accepts.
Scene load_model_window(const std::string& path, std::size_t max_triangles, const ModelWindow& window,
                        std::uint64_t& fans, std::size_t block_bytes = std::size_t(32) << 20);

}  // namespace opsila
