// The checks of each format before the importer reads it: text nesting
// here, OFF's in off_checks.cpp, glTF's in gltf_checks.cpp, PLY's and STL's
// in their own rooms (formats/ply/ply_format.h, formats/stl/stl_format.h).
#include "formats/assimp/model_checks.h"

#include <algorithm>
#include <cstdint>
#include <string_view>

#include "core/env_hooks.h"
#include "core/errors.h"
#include "core/host_memory.h"
#include "core/input_file.h"
#include "core/util.h"
#include "formats/ply/ply_format.h"
#include "formats/ply/ply_reader.h"
#include "scene/triangle_limit.h"
#include "formats/stl/stl_format.h"

namespace opsila {

namespace {

// Depth of XML element nesting (comments, CDATA, declarations and quoted
// attribute values skipped), or of braces outside quotes for other text.
long nesting_depth(std::string_view text, bool xml) {
  long depth = 0, deepest = 0;
  const auto skip_to = [&](std::size_t& i, std::string_view end) {
    const std::size_t at = text.find(end, i);
    i = at == std::string_view::npos ? text.size() : at + end.size() - 1;
  };
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (!xml) {
      if (c == '"') skip_to(++i, "\"");
      else if (c == '{') deepest = std::max(deepest, ++depth);
      else if (c == '}') --depth;
      continue;
    }
    if (c != '<' || i + 1 >= text.size()) continue;
    const char next = text[i + 1];
    if (text.compare(i, 4, "<!--") == 0) skip_to(i, "-->");
    else if (text.compare(i, 9, "<![CDATA[") == 0) skip_to(i, "]]>");
    else if (next == '?') skip_to(i, "?>");
    else if (next == '!') skip_to(i, ">");
    else if (next == '/') --depth, skip_to(i, ">");
    else {
      char quote = 0;
      std::size_t j = i + 1;
      for (; j < text.size() && (quote || text[j] != '>'); ++j)
        if (quote ? text[j] == quote : text[j] == '"' || text[j] == '\'') quote = quote ? 0 : text[j];
      if (j < text.size() && text[j - 1] != '/') deepest = std::max(deepest, ++depth);
      i = j;
    }
  }
  return deepest;
}

}  // namespace

// The importer's other readers (COLLADA, X3D, DirectX .x, ASE, FBX text, ...)
// recurse once per level of nesting, and their node hierarchies are known
// only after the import: a 2-million-level COLLADA file overflowed even the
// import thread's stack. Text nested deeper than kMaxNesting is refused
// first. Binary files (a NUL in the first 64 KiB) are left to the importer.
void check_nesting(const std::string& bytes, const std::string& name) {
  const std::string_view head = std::string_view(bytes).substr(0, 64 * 1024);
  if (head.find('\0') != std::string_view::npos) return;
  std::size_t first = head.find_first_not_of(" \t\r\n");
  if (head.compare(0, 3, "\xEF\xBB\xBF") == 0) first = head.find_first_not_of(" \t\r\n", 3);
  const bool xml = first != std::string_view::npos && head[first] == '<';
  const long depth = nesting_depth(bytes, xml);
  if (depth > kMaxNesting)
    throw InputError(name + ": " + (xml ? "XML elements" : "braces") + " nested " + std::to_string(depth) +
                     " levels deep (the limit is " + std::to_string(kMaxNesting) + ")");
}

std::uint64_t import_memory_budget(std::uint64_t bytes) {
  if (const auto v = env_hook_number(EnvHook::import_memory, 1, std::uint64_t(1) << 50, "a number of bytes"))
    return *v;
  const std::uint64_t ram = physical_memory();
  const std::uint64_t want = std::max<std::uint64_t>(std::uint64_t(1) << 30, 64 * std::min<std::uint64_t>(bytes, std::uint64_t(1) << 50));
  return ram > 0 ? std::max<std::uint64_t>(std::min(want, ram / 4 * 3), std::uint64_t(1) << 30) : want;
}

std::uint64_t check_model_file_shape(ModelFiles& files, const std::string& path, const std::string& ext) {
  const std::string e = lower(!ext.empty() && ext[0] == '.' ? ext.substr(1) : ext);
  const std::uint64_t size = files.size(path);
  if (e == "off") {
    check_off(files.head(path, kMaxInputFileBytes), static_cast<std::size_t>(size), path);
    return size;
  }
  const std::string bytes = files.head(path, kMaxInputFileBytes);
  // The importer's text readers take bytes, not UTF-16: an ASE read a
  // fraction of its meshes, an AC3D or COLLADA nothing, in their own words.
  // STL's check says it in STL's terms (a binary STL's header is any bytes).
  if (e != "stl" && (bytes.rfind("\xff\xfe", 0) == 0 || bytes.rfind("\xfe\xff", 0) == 0))
    throw InputError(path + ":1: UTF-16 text is not supported (save the file as UTF-8 or ASCII)");
  if (e == "ply") {
    ply::check_ply(bytes, path);
    check_ply_text(path, kMaxTriangles, &bytes);  // as ranks read it
  } else if (e == "stl") stl::check_stl(bytes, path);
  else if (e == "gltf" || e == "glb") return size + check_gltf(files, bytes, path);
  else check_nesting(bytes, path);
  if (e == "fbx") {
    check_fbx_text(bytes, path);
    check_fbx_binary(bytes, path);
  }
  if (e == "md5mesh") check_md5_mesh(bytes, path);
  if (e == "ase" || e == "ask") check_ase(bytes, path);
  if (e == "ac" || e == "acc" || e == "ac3d") check_ac3d(bytes, path);
  if (e == "x") check_x_text(bytes, path);
  if (e == "dae") check_collada(bytes, path);
  return size;
}

}  // namespace opsila
