#include "formats/assimp/gltf_uris.h"

namespace opsila {

namespace {

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

void decode_uri(nlohmann::json& entry, const std::string& dir,
                const std::function<bool(const std::string&)>& exists, bool& changed) {
  if (!entry.is_object()) return;
  const auto uri = entry.find("uri");
  if (uri == entry.end() || !uri->is_string()) return;
  const std::string& written = uri->get_ref<const std::string&>();
  if (written.compare(0, 5, "data:") == 0) return;
  const std::optional<std::string> decoded = percent_decoded(written);
  // A decoding that reads as a data URI would change what the importer does.
  if (!decoded || decoded->compare(0, 5, "data:") == 0) return;
  if (!exists(dir.empty() ? *decoded : dir + "/" + *decoded)) return;
  try {  // the JSON handed on must be UTF-8, as the decoded name may not be
    (void)nlohmann::json(*decoded).dump();
  } catch (const nlohmann::json::type_error&) {
    return;
  }
  *uri = *decoded;
  changed = true;
}

}  // namespace

std::optional<std::string> percent_decoded(const std::string& uri) {
  if (uri.find('%') == std::string::npos) return std::nullopt;
  std::string out;
  out.reserve(uri.size());
  for (std::size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] != '%') {
      out += uri[i];
      continue;
    }
    const int hi = i + 2 < uri.size() ? hex_value(uri[i + 1]) : -1, lo = hi >= 0 ? hex_value(uri[i + 2]) : -1;
    if (lo < 0 || (hi == 0 && lo == 0)) return std::nullopt;
    out += char(hi * 16 + lo);
    i += 2;
  }
  return out;
}

bool decode_gltf_uris(nlohmann::json& root, const std::string& dir,
                      const std::function<bool(const std::string&)>& exists) {
  bool changed = false;
  for (const char* collection : {"buffers", "images"}) {
    const auto it = root.find(collection);
    if (it == root.end() || !it->is_structured()) continue;
    for (nlohmann::json& entry : *it) decode_uri(entry, dir, exists, changed);
  }
  return changed;
}

}  // namespace opsila
