#include "formats/assimp/model_window.h"

#include <filesystem>

#include "core/util.h"
#include "formats/ply/ply_reader.h"
#include "formats/stl/stl_reader.h"

namespace opsila {

namespace {

std::string extension(const std::string& path) { return lower(std::filesystem::path(path).extension().string()); }

}  // namespace

bool is_streamed_model(const std::string& path) {
  const std::string ext = extension(path);
  return ext == ".ply" || ext == ".stl";
}

std::string model_stream_refusal(const std::string& path) {
  const std::string ext = extension(path);
  if (ext == ".ply") return ply_stream_refusal(path);
  if (ext == ".stl") return stl_stream_refusal(path);
  return "no stream reads this format";
}

Scene load_model_window(const std::string& path, std::size_t max_triangles, const ModelWindow& window,
                        std::uint64_t& fans, std::size_t block_bytes) {
  if (extension(path) == ".stl") return load_stl_window(path, max_triangles, window, fans, block_bytes);
  return load_ply_window(path, max_triangles, window, fans, block_bytes);
}

}  // namespace opsila
