// The still scene of a glTF. opsila renders a model's meshes as they are
// stored (the bind pose) and never uses its skins or animations, but the
// importer reads them: Debian's assimp 5.2 faults on a skin without
// inverseBindMatrices (glTF 2 makes them optional: identity matrices) and
// allocates every animation channel's keys. A model that has either is
// handed to the importer without them: its JSON rewritten (values as they
// were), a GLB's container rebuilt around it, its other chunks unchanged.
#pragma once

#include <optional>
#include <string>

#include <nlohmann/json.hpp>

namespace opsila {

// `bytes`, a glTF's text or a GLB whose lengths the checks have read, with
// JSON `root`: the same without skins, animations and the nodes' skin
// references; nothing when there are none and `rewritten` is false (set it
// when `root` differs from the JSON in `bytes`).
std::optional<std::string> gltf_without_motion(const nlohmann::json& root, const std::string& bytes,
                                               bool rewritten = false);

}  // namespace opsila
