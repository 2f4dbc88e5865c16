// The files a glTF's buffers and images name. glTF writes each name as a
// URI (RFC 3986): reserved characters and spaces percent-encoded, so
// "Brick%20Wall.png" is the file "Brick Wall.png". The importer opens the
// name as written; exporters differ (some encode, some write names as they
// are), so a name whose decoding is a file that exists means that file, and
// any other name means itself.
#pragma once

#include <functional>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

namespace opsila {

// `uri` with its %XX escapes decoded; nothing when it has none, when an
// escape is not two hex digits, or when one decodes to NUL.
std::optional<std::string> percent_decoded(const std::string& uri);

// Replaces each buffer's and image's uri (glTF 2 arrays, glTF 1 objects; not
// data: URIs) by its decoding where `exists(dir/decoded)` and the decoding
// differs; returns whether any changed.
bool decode_gltf_uris(nlohmann::json& root, const std::string& dir,
                      const std::function<bool(const std::string&)>& exists);

}  // namespace opsila
