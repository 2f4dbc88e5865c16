// glTF and GLB checks before the importer reads the file. The importer
// allocates a GLB chunk as long as its header says, reads external buffers
// whole, checks bufferView ranges in arithmetic that wraps near 2^64 (and
// then reads outside the buffer), and recurses once per node level. Both
// glTF 2 (collections are arrays) and glTF 1 (objects keyed by id) are read.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <unordered_map>
#include <vector>

#include <nlohmann/json.hpp>

#include "formats/common/json_text.h"
#include "formats/common/model_words.h"
#include "formats/assimp/glb_container.h"
#include "formats/assimp/gltf_still.h"
#include "formats/assimp/gltf_uris.h"
#include "formats/assimp/model_checks.h"
#include "formats/obj/obj_loader.h"

namespace opsila {

namespace {

using Json = nlohmann::json;
using u64 = std::uint64_t;

// A count, offset, length or index: a whole number >= 0 (2^64 and beyond
// read as the largest u64, which no range holds).
u64 whole(const Json& obj, const char* key, u64 fallback, const std::string& where) {
  const auto it = obj.find(key);
  if (it == obj.end()) return fallback;
  if (it->is_number_unsigned()) return it->get<u64>();
  if (it->is_number_float()) {
    const double d = it->get<double>();
    if (d >= 0 && d == std::floor(d)) return d >= 18446744073709551615.0 ? ~u64(0) : u64(d);
  }
  throw InputError(where + ": '" + key + "' is not a whole number >= 0");
}

// The entries of a top-level collection, with the names messages give them.
struct Entry {
  std::string where, key;  // key: the glTF 1 id ("" in glTF 2)
  const Json* value;
};

class Gltf {
 public:
  Gltf(const Json& root, const std::string& name) : root_(root), name_(name) {}

  std::vector<Entry> entries(const char* collection) const {
    std::vector<Entry> out;
    const auto it = root_.find(collection);
    if (it == root_.end()) return out;
    if (it->is_array())
      for (std::size_t i = 0; i < it->size(); ++i)
        out.push_back({name_ + ": " + collection + "[" + std::to_string(i) + "]", "", &(*it)[i]});
    else if (it->is_object())
      for (auto e = it->begin(); e != it->end(); ++e)
        out.push_back({name_ + ": " + collection + " '" + quoted_prefix(e.key()) + "'", e.key(), &e.value()});
    return out;
  }
  // Index of the entry `ref` names in `collection`, or -1.
  long index(const char* collection, const Json& ref) const {
    const auto it = root_.find(collection);
    if (it == root_.end()) return -1;
    if (it->is_array() && ref.is_number_unsigned() && ref.get<u64>() < it->size()) return long(ref.get<u64>());
    if (it->is_object() && ref.is_string()) {
      std::unordered_map<std::string, long>& ids = ids_[collection];
      if (ids.empty()) {
        long k = 0;
        for (auto e = it->begin(); e != it->end(); ++e) ids.emplace(e.key(), k++);
      }
      const auto k = ids.find(ref.get_ref<const std::string&>());
      if (k != ids.end()) return k->second;
    }
    return -1;
  }
  // `obj[key]` as a reference into `collection` (an index into `lengths`).
  long ref(const Json& obj, const char* key, const char* collection, const std::string& where) const {
    const auto it = obj.find(key);
    if (it == obj.end()) return -1;
    const long k = index(collection, *it);
    if (k < 0) throw InputError(where + ": '" + key + "' names no entry of '" + collection + "'");
    return k;
  }

 private:
  const Json& root_;
  const std::string& name_;
  mutable std::unordered_map<std::string, std::unordered_map<std::string, long>> ids_;  // glTF 1 id -> index
};

// Bytes a data: URI holds (base64 decoded, else its text). Base64 must be
// whole: the importer decodes a character outside the alphabet as some
// value and reads other geometry than the file's, without a word.
u64 data_uri_bytes(const std::string& uri, const std::string& where) {
  const std::size_t comma = uri.find(',');
  if (comma == std::string::npos) return 0;
  const u64 text = uri.size() - comma - 1;
  if (uri.rfind(";base64", comma) == std::string::npos) return text;
  const std::size_t end = uri.find_last_not_of('=') + 1, bad = uri.find_first_not_of(
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/", comma + 1);
  if ((bad != std::string::npos && bad < end) || uri.size() - end > 2 || text % 4 != 0)
    throw InputError(where + ": uri: the data URI is not base64" +
                     (bad < end ? " (character " + std::to_string(bad - comma) + " of its data is not in the alphabet)"
                                : " (its length is not a multiple of 4 with at most two '=' at the end)"));
  u64 pad = 0;
  for (std::size_t k = uri.size(); k > comma + 1 && uri[k - 1] == '=' && pad < 2; --k) ++pad;
  return text / 4 * 3 - std::min<u64>(pad, text / 4 * 3);
}

// Each buffer's length; `external` gets the bytes of the files they name.
std::vector<u64> buffer_lengths(const Gltf& g, ModelFiles& files, const GltfParts& parts, const std::string& path,
                                u64& external) {
  std::vector<u64> lengths;
  for (const Entry& e : g.entries("buffers")) {
    u64 available = parts.bin_bytes;  // no uri: the GLB's binary chunk
    std::string source = "the GLB binary chunk";
    const auto uri = e.value->find("uri");
    // In a GLB 2 the importer reads buffer 0 from the BIN chunk whatever
    // its uri says (a file's bytes were drawn from a chunk of zeros).
    if (parts.glb_version == 2 && lengths.empty() && uri != e.value->end())
      throw InputError(e.where + ": a uri in a GLB file (the importer reads buffer 0 from the GLB's BIN chunk "
                                 "whatever the uri names): give it no uri, or write the model as .gltf");
    if (uri != e.value->end() && uri->is_string() && e.key != "binary_glTF") {
      const std::string& u = uri->get_ref<const std::string&>();
      if (u.compare(0, 5, "data:") == 0) {
        available = data_uri_bytes(u, e.where);
        source = "its data URI";
      } else {
        // Where the importer looks: the model's folder and the uri as written.
        const std::string dir = std::filesystem::path(path).parent_path().string();
        source = dir.empty() ? u : dir + "/" + u;
        try {
          available = files.size(source);
        } catch (const InputError& x) {  // the file's own words, after the key that names it
          throw InputError(e.where + ": uri " + model_words::quote(u) + ": " + x.what());
        }
        external += available;
      }
    }
    const u64 length = whole(*e.value, "byteLength", available, e.where);
    if (length > available)
      throw InputError(e.where + ": byteLength " + std::to_string(length) + " but " + source + " holds " +
                       std::to_string(available) + " bytes");
    lengths.push_back(length);
  }
  return lengths;
}

struct View {
  u64 length = 0, stride = 0;
};

std::vector<View> buffer_views(const Gltf& g, const std::vector<u64>& buffers) {
  std::vector<View> views;
  for (const Entry& e : g.entries("bufferViews")) {
    const long b = g.ref(*e.value, "buffer", "buffers", e.where);
    if (b < 0) throw InputError(e.where + ": no 'buffer'");
    const u64 offset = whole(*e.value, "byteOffset", 0, e.where);
    const u64 length = whole(*e.value, "byteLength", 0, e.where);
    // An image in a view of no bytes was dropped without a word.
    if (length == 0) throw InputError(e.where + ": byteLength 0 or none (a buffer view holds at least 1 byte)");
    if (offset > buffers[b] || length > buffers[b] - offset)
      throw InputError(e.where + ": byteOffset " + std::to_string(offset) + " + byteLength " + std::to_string(length) +
                       " runs past the end of its buffer (" + std::to_string(buffers[b]) + " bytes)");
    const u64 stride = whole(*e.value, "byteStride", 0, e.where);
    if (stride > 255) throw InputError(e.where + ": byteStride " + std::to_string(stride) + " (at most 252)");
    views.push_back({length, stride});
  }
  return views;
}

u64 component_bytes(u64 type) {
  switch (type) {
    case 5120: case 5121: return 1;
    case 5122: case 5123: return 2;
    case 5125: case 5126: return 4;
    default: return 0;
  }
}

u64 type_components(const Json& obj) {
  const auto it = obj.find("type");
  if (it == obj.end() || !it->is_string()) return 0;
  static const std::unordered_map<std::string, u64> kCounts = {
      {"SCALAR", 1}, {"VEC2", 2}, {"VEC3", 3}, {"VEC4", 4}, {"MAT2", 4}, {"MAT3", 9}, {"MAT4", 16}};
  const auto k = kCounts.find(it->get<std::string>());
  return k == kCounts.end() ? 0 : k->second;
}

// `count` elements of `elem` bytes, `stride` apart, from `offset` fit in a
// view of `length` bytes (64-bit arithmetic that cannot wrap).
void check_range(u64 offset, u64 count, u64 elem, u64 stride, u64 length, const std::string& where,
                 const std::string& view) {
  if (count == 0) return;
  const u64 step = std::max(stride, elem);
  if (offset > length || elem > length - offset || count - 1 > (length - offset - elem) / std::max<u64>(step, 1))
    throw InputError(where + ": " + std::to_string(count) + " element(s) of " + std::to_string(elem) +
                     " bytes from byteOffset " + std::to_string(offset) + " run past the end of " + view + " (" +
                     std::to_string(length) + " bytes)");
}

// What an accessor holds: `count` elements of `elem` bytes.
struct Accessor {
  std::string where;
  u64 count = 0, elem = 0;
};

std::vector<Accessor> check_accessors(const Gltf& g, const std::vector<View>& views) {
  std::vector<Accessor> accessors;
  for (const Entry& e : g.entries("accessors")) {
    const Json& a = *e.value;
    const u64 comp = component_bytes(whole(a, "componentType", 0, e.where)), n = type_components(a);
    if (comp == 0 || n == 0) throw InputError(e.where + ": unknown componentType or type");
    const u64 count = whole(a, "count", 0, e.where), elem = comp * n;
    accessors.push_back({e.where, count, elem});
    if (count > kMaxInputFileBytes / elem)
      throw InputError(e.where + ": count " + std::to_string(count) + " (more than a file can hold)");
    const long v = g.ref(a, "bufferView", "bufferViews", e.where);
    if (v >= 0) {
      const u64 stride = whole(a, "byteStride", views[v].stride, e.where);  // glTF 1 keeps it here
      // glTF: a stride, where given, holds at least one element; a smaller
      // one makes elements overlap, and the importer would read garbage.
      if (stride != 0 && stride < elem)
        throw InputError(e.where + ": byteStride " + std::to_string(stride) + " of bufferViews[" + std::to_string(v) +
                         "] is smaller than one element (" + std::to_string(elem) + " bytes)");
      check_range(whole(a, "byteOffset", 0, e.where), count, elem, stride, views[v].length, e.where,
                  "bufferViews[" + std::to_string(v) + "]");
    }
    const auto sparse = a.find("sparse");
    if (sparse == a.end() || !sparse->is_object()) continue;
    const std::string where = e.where + ".sparse";
    const u64 changed = whole(*sparse, "count", 0, where);
    if (changed > count) throw InputError(where + ": count " + std::to_string(changed) + " exceeds the accessor's");
    for (const char* part : {"indices", "values"}) {
      const auto p = sparse->find(part);
      if (p == sparse->end() || !p->is_object()) throw InputError(where + ": no '" + part + "'");
      const std::string at = where + "." + part;
      const u64 bytes = part[0] == 'i' ? component_bytes(whole(*p, "componentType", 0, at)) : elem;
      if (bytes == 0) throw InputError(at + ": unknown componentType");
      const long pv = g.ref(*p, "bufferView", "bufferViews", at);
      if (pv < 0) throw InputError(at + ": no 'bufferView'");
      check_range(whole(*p, "byteOffset", 0, at), changed, bytes, bytes, views[pv].length, at,
                  "bufferViews[" + std::to_string(pv) + "]");
    }
  }
  return accessors;
}

// A node's placement as glTF writes it: a matrix of 16 numbers, or a
// translation and scale of 3 and a rotation of 4, a unit quaternion (the
// importer takes any array and any quaternion: the zero one placed the
// mesh as a point), or a projective matrix (placed as if affine).
void check_node_transform(const Entry& n) {
  static const std::pair<const char*, std::size_t> kKeys[] = {
      {"matrix", 16}, {"translation", 3}, {"rotation", 4}, {"scale", 3}};
  for (const auto& [key, size] : kKeys) {
    const auto it = n.value->find(key);
    if (it == n.value->end()) continue;
    bool numbers = it->is_array() && it->size() == size;
    double norm = 0;
    for (std::size_t k = 0; numbers && k < size; ++k) {
      numbers = (*it)[k].is_number() && std::isfinite((*it)[k].get<double>());
      if (numbers) norm += (*it)[k].get<double>() * (*it)[k].get<double>();
    }
    if (!numbers)
      throw InputError(n.where + ": '" + key + "' is not " + std::to_string(size) + " finite numbers");
    if (size == 4 && std::fabs(norm - 1.0) > 1e-2)
      throw InputError(n.where + ": 'rotation' is not a unit quaternion (its length is " + std::to_string(std::sqrt(norm)) + ")");
    if (size == 16 && ((*it)[3] != 0 || (*it)[7] != 0 || (*it)[11] != 0 || (*it)[15] != 1))  // the importer took w as 1
      throw InputError(n.where + ": 'matrix' is not affine (its last row, elements 3, 7, 11, 15, is not 0 0 0 1)");
  }
}

// The node graph is a forest (glTF: "disjoint strict trees") of bounded
// size and depth; the depth of every node is found without recursion.
void check_nodes(const Gltf& g, const std::string& name) {
  const std::vector<Entry> nodes = g.entries("nodes");
  if (nodes.size() > kMaxNodes)
    throw InputError(name + ": " + std::to_string(nodes.size()) + " nodes (the limit is " +
                     std::to_string(kMaxNodes) + ")");
  std::vector<long> parent(nodes.size(), -1);
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    check_node_transform(nodes[i]);
    const auto children = nodes[i].value->find("children");
    if (children == nodes[i].value->end() || !children->is_array()) continue;
    for (const Json& c : *children) {
      const long k = g.index("nodes", c);
      if (k < 0) throw InputError(nodes[i].where + ": a child names no node");
      if (parent[k] >= 0 || k == long(i))
        throw InputError(nodes[k].where + ": has two parents or is its own child (nodes must form trees)");
      parent[k] = long(i);
    }
  }
  std::vector<long> depth(nodes.size(), -1), path;
  long deepest = 0;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    long j = long(i);
    path.clear();
    while (j >= 0 && depth[j] < 0) {
      if (path.size() > nodes.size()) throw InputError(nodes[i].where + ": is its own ancestor (a cycle)");
      path.push_back(j);
      j = parent[j];
    }
    long d = j >= 0 ? depth[j] : -1;
    for (auto k = path.rbegin(); k != path.rend(); ++k) depth[*k] = ++d;
    deepest = std::max(deepest, d);
  }
  if (deepest > kMaxNodeDepth)
    throw InputError(name + ": node hierarchy " + std::to_string(deepest) + " levels deep (the limit is " +
                     std::to_string(kMaxNodeDepth) + ")");
}

// The importer's memory for what a scene uses, about (Debian's assimp 5.2):
// it reads only the accessors a mesh uses (skins and animations are not
// read, gltf_still.h), each whole
// for every use (its bytes, then vectors of 12 to 16 bytes an element); an
// index becomes a face of 16 bytes with an array of its own; a primitive,
// node or material is a record of a few KiB (a name is a 1 KiB array). An
// accessor with no bufferView, or a sparse one, holds as many elements as
// its count says with none of their bytes in the file: a 700-byte glTF had
// the importer ask for 12.9 GB (found by fuzz_model).
class ImportCost {
 public:
  static constexpr u64 kVertexBytes = 32, kIndexBytes = 64, kRecordBytes = 2048;
  ImportCost(const Gltf& g, const std::vector<Accessor>& accessors) : g_(g), accessors_(accessors) {}

  // `ref` names an accessor read at `where`, `per_element` bytes an element
  // beyond its own; returns its count.
  u64 use(const Json& ref, u64 per_element, const std::string& where) {
    const long k = g_.index("accessors", ref);
    if (k < 0) throw InputError(where + ": names no entry of 'accessors'");
    const Accessor& a = accessors_[std::size_t(k)];
    add(a.count * (a.elem + per_element), where, &a);
    return a.count;
  }
  void add(u64 bytes, const std::string& where, const Accessor* a = nullptr) {
    total_ += bytes;
    if (bytes <= largest_) return;
    largest_ = bytes;
    largest_where_ = where;
    largest_accessor_ = a;
  }
  void check(u64 budget) const {
    if (total_ <= budget) return;
    std::string what = largest_where_;
    if (largest_accessor_)
      what += " (" + largest_accessor_->where.substr(largest_accessor_->where.find(": ") + 2) + ", " +
              std::to_string(largest_accessor_->count) + " elements)";
    const auto size = [](u64 b) { return b >> 20 ? std::to_string(b >> 20) + " MiB" : std::to_string(b) + " bytes"; };
    throw InputError(what + ": importing the model would take about " + size(total_) + ", more than the " +
                     size(budget) + " the model importer may use (1 GiB or 64 times the file and its buffers; " +
                     "OPSILA_IMPORT_MEMORY)");
  }

 private:
  const Gltf& g_;
  const std::vector<Accessor>& accessors_;
  u64 total_ = 0, largest_ = 0;
  std::string largest_where_;
  const Accessor* largest_accessor_ = nullptr;
};

// The vertex attributes of `obj` (a primitive or one of its morph targets).
// With no indices, the importer makes a face of every few vertices: the
// attribute that holds the most elements is used again for them.
void use_attributes(ImportCost& cost, const Json& obj, const std::string& where, bool faces) {
  if (!obj.is_object()) return;
  u64 most = 0;
  auto longest = obj.end();
  for (auto a = obj.begin(); a != obj.end(); ++a) {
    const u64 n = cost.use(a.value(), ImportCost::kVertexBytes, where + "." + quoted_prefix(a.key()));
    if (longest == obj.end() || n > most) most = n, longest = a;
  }
  if (faces && longest != obj.end())
    cost.use(longest.value(), ImportCost::kIndexBytes, where + "." + quoted_prefix(longest.key()));
}

void use_meshes(const Gltf& g, ImportCost& cost) {
  for (const Entry& m : g.entries("meshes")) {
    const auto prims = m.value->find("primitives");
    if (prims == m.value->end() || !prims->is_array()) continue;
    for (std::size_t i = 0; i < prims->size(); ++i) {
      const Json& p = (*prims)[i];
      const std::string where = m.where + ".primitives[" + std::to_string(i) + "]";
      if (!p.is_object()) continue;
      cost.add(ImportCost::kRecordBytes, where);
      g.ref(p, "material", "materials", where);  // the importer: 'Missing section "materials"'
      // The importer drew a mode of 4294967296 as triangles.
      if (const u64 mode = whole(p, "mode", 4, where); mode > 6)
        throw InputError(where + ": mode " + std::to_string(mode) + " (a glTF primitive's mode is 0 to 6)");
      const auto indices = p.find("indices"), attributes = p.find("attributes"), targets = p.find("targets");
      if (indices != p.end()) cost.use(*indices, ImportCost::kIndexBytes, where + ".indices");
      if (attributes != p.end()) use_attributes(cost, *attributes, where + ".attributes", indices == p.end());
      if (targets != p.end() && targets->is_array())
        for (std::size_t t = 0; t < targets->size(); ++t)
          use_attributes(cost, (*targets)[t], where + ".targets[" + std::to_string(t) + "]", false);
    }
  }
}

// A record per node and material. Skins and animations are not read
// (gltf_still.h).
void use_records(const Gltf& g, ImportCost& cost) {
  for (const char* records : {"nodes", "materials"})
    for (const Entry& e : g.entries(records)) cost.add(ImportCost::kRecordBytes, e.where);
}

void check_import_memory(const Gltf& g, const std::vector<Accessor>& accessors, u64 budget) {
  ImportCost cost(g, accessors);
  use_meshes(g, cost);
  use_records(g, cost);
  cost.check(budget);
}

// Mesh compressions the importer cannot decode (Debian's assimp 5.2 reads
// Draco, not meshopt): a file that requires one would otherwise fail on its
// placeholder buffers, with a message about their lengths.
void check_required_extensions(const Json& root, const std::string& name) {
  static const char* const kUndecodable[] = {"EXT_meshopt_compression", "KHR_meshopt_compression"};
  const auto required = root.find("extensionsRequired");
  if (required == root.end() || !required->is_array()) return;
  for (const Json& e : *required)
    for (const char* extension : kUndecodable)
      if (e.is_string() && e.get_ref<const std::string&>() == extension)
        throw InputError(name + ": extensionsRequired names " + extension +
                         " (meshopt-compressed meshes), which the model importer cannot decode: save the model "
                         "without mesh compression");
}

// A key given twice in one object: the importer reads the first, these
// checks (nlohmann) the last, so a bad value placed first passed them all
// (a matrix that is not affine, a bufferView whose offset wraps 2^64).
void refuse_repeated_keys(const std::string& json, const std::string& path) {
  std::vector<std::string> repeated;
  const JsonLines lines(json, path, repeated);
  if (repeated.empty()) return;
  std::string first = repeated.front();
  first.resize(first.rfind("; the last one is used"));
  throw InputError(first + " (the model importer reads the first, these checks the last: give each key once)");
}

}  // namespace

std::uint64_t check_gltf(ModelFiles& files, const std::string& bytes, const std::string& path) {
  GltfParts parts;
  if (bytes.compare(0, 4, "glTF") == 0) parts = split_glb(bytes, path);
  else parts.json = bytes;
  // The importer's JSON reader recurses once per level of nesting, and cuts
  // a name (a buffer's or an image's uri) at a NUL.
  check_json_shape(parts.json, path, 64, 1 << 24);
  check_json_nul_escapes(parts.json, path);
  // Not a JSON object: no glTF reader takes it (and no other is asked).
  const std::size_t first = parts.json.find_first_not_of(" \t\r\n");
  if (first == std::string::npos || parts.json[first] != '{') return 0;
  Json root;
  try {
    root = Json::parse(parts.json);
  } catch (const Json::exception& e) {
    // "[json.exception.parse_error.101] parse error at ...; last read: '...'", where
    // what was last read may be a whole data URI: shown cut short.
    const std::string why = e.what();
    throw InputError(path + ": not glTF JSON (" + model_words::one_line(why.substr(why.find(']') + 2), 200) + ")");
  }
  if (!root.is_object()) throw InputError(path + ": not glTF JSON (not an object)");
  refuse_repeated_keys(parts.json, path);
  check_required_extensions(root, path);
  check_gltf_meanings(root, path);
  // Percent-encoded names: checked, and handed to the importer, decoded.
  const std::string dir = std::filesystem::path(path).parent_path().string();
  const bool decoded = decode_gltf_uris(root, dir, [&](const std::string& p) { return files.exists(p); });
  const Gltf g(root, path);
  u64 external = 0;
  const std::vector<u64> buffers = buffer_lengths(g, files, parts, path, external);
  const std::vector<Accessor> accessors = check_accessors(g, buffer_views(g, buffers));
  check_nodes(g, path);
  check_import_memory(g, accessors, import_memory_budget(files.size(path) + external));
  if (const auto still = gltf_without_motion(root, bytes, decoded)) files.substitute(path, *still);
  return external;
}

}  // namespace opsila
