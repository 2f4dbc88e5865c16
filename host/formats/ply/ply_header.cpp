// A PLY header, read strictly, and whether the PLY stream reads the file
// exactly as the importer path does.
#include <algorithm>
#include <sstream>

#include "core/errors.h"
#include "core/util.h"
#include "formats/common/model_files.h"
#include "formats/ply/ply_format.h"

namespace opsila {
namespace ply {

namespace {

constexpr std::size_t kMaxHeaderBytes = 64 * 1024;  // the importer path's check_ply limit

bool type_named(const std::string& name, Type& t) {
  static const std::pair<const char*, Type> kTypes[] = {
      {"char", Type::int8},     {"int8", Type::int8},       {"uchar", Type::uint8},    {"uint8", Type::uint8},
      {"short", Type::int16},   {"int16", Type::int16},     {"ushort", Type::uint16},  {"uint16", Type::uint16},
      {"int", Type::int32},     {"int32", Type::int32},     {"uint", Type::uint32},    {"uint32", Type::uint32},
      {"float", Type::float32}, {"float32", Type::float32}, {"double", Type::float64}, {"float64", Type::float64}};
  for (const auto& [n, type] : kTypes)
    if (name == n) return t = type, true;
  return false;
}

struct HeaderLines {
  const std::string& path;
  Header& h;
  int line = 0;

  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(path + ":" + std::to_string(line) + ": PLY header: " + what);
  }
  Type type(const std::string& name) const {
    Type t;
    if (!type_named(name, t)) fail("unknown property type '" + name.substr(0, 20) + "'");
    return t;
  }
  void element(std::istringstream& words) {
    std::string name, count, extra;
    words >> name >> count >> extra;
    if (name.empty() || count.empty() || !extra.empty() || count.size() > 19 ||
        count.find_first_not_of("0123456789") != std::string::npos)
      fail("'element NAME COUNT' expected");
    for (const Element& e : h.elements)
      if (e.name == name) fail("the element '" + name.substr(0, 20) + "' is declared twice");
    h.elements.push_back(Element{name, std::stoull(count), {}, line});
  }
  void property(std::istringstream& words) {
    if (h.elements.empty()) fail("a property before any element");
    std::string a, b, c, d, extra;
    words >> a >> b >> c >> d >> extra;
    Property p;
    if (a == "list") {
      if (d.empty() || !extra.empty()) fail("'property list COUNT_TYPE TYPE NAME' expected");
      p.list = true, p.count = type(b), p.type = type(c), p.name = d;
    } else {
      if (b.empty() || !c.empty()) fail("'property TYPE NAME' expected");
      p.type = type(a), p.name = b;
    }
    h.elements.back().properties.push_back(p);
  }
  // One line; true at 'end_header'.
  bool read(const std::string& text, bool& format_seen) {
    std::istringstream words(text);
    std::string keyword;
    words >> keyword;
    if (keyword == "end_header") return true;
    if (keyword == "comment" || keyword == "obj_info") {
      h.comments.push_back(text.substr(std::min(text.size(), text.find(keyword) + keyword.size())));
    } else if (keyword == "format") {
      std::string f, version, extra;
      words >> f >> version >> extra;
      if (format_seen || version != "1.0" || !extra.empty()) fail("'format TYPE 1.0' expected once");
      if (f == "ascii") h.format = Format::ascii;
      else if (f == "binary_little_endian") h.format = Format::little_endian;
      else if (f == "binary_big_endian") h.format = Format::big_endian;
      else fail("format '" + f.substr(0, 20) + "' (ascii, binary_little_endian or binary_big_endian)");
      format_seen = true;
    } else if (keyword == "element") {
      if (!format_seen) fail("an element before the format line");
      element(words);
    } else if (keyword == "property") {
      property(words);
    } else if (!keyword.empty()) {
      fail("unknown line '" + keyword.substr(0, 20) + "'");
    } else {
      fail("empty line");
    }
    return false;
  }
};

}  // namespace

Header read_header(const std::string& path) {
  ModelFiles files;
  Header h;
  h.file_bytes = files.size(path);
  const std::string head = files.head(path, kMaxHeaderBytes);
  HeaderLines lines{path, h};
  bool format_seen = false;
  std::size_t at = 0;
  while (true) {
    const std::size_t nl = head.find('\n', at);
    ++lines.line;
    if (nl == std::string::npos)
      throw InputError(path + ": PLY header without an 'end_header' line (truncated or not PLY)");
    std::string text = head.substr(at, nl - at);
    if (!text.empty() && text.back() == '\r') text.pop_back();
    at = nl + 1;
    if (lines.line == 1) {
      if (text != "ply") throw InputError(path + ": not PLY (a PLY file starts with the line 'ply')");
      continue;
    }
    if (lines.read(text, format_seen)) break;
  }
  if (!format_seen) lines.fail("no format line");
  h.body = at;
  h.lines = lines.line;
  return h;
}

bool has_strips(const Header& h) {
  for (const Element& e : h.elements)
    if (e.name == "tristrips") return true;
  return false;
}

std::string stream_refusal(const Header& h) {
  // 'vertex', then 'face' or 'tristrips' or both in that order (faces'
  // facet ids come first either way).
  const auto named = [&](std::size_t k, const char* n) { return h.elements.size() > k && h.elements[k].name == n; };
  const bool faces = named(1, "face"), strips = named(faces ? 2 : 1, "tristrips");
  if (!named(0, "vertex") || h.elements.size() != 1u + faces + strips || h.elements.size() < 2)
    return "its elements are not 'vertex' then 'face' (or 'tristrips', or both)";
  for (const std::string& c : h.comments)
    if (lower(c).find("texture") != std::string::npos) return "a comment names a texture";
  for (std::size_t k = 1; k < h.elements.size(); ++k) {
    const Element& face = h.elements[k];
    if (face.properties.size() != 1 || !face.properties[0].list ||
        (face.properties[0].name != "vertex_indices" && face.properties[0].name != "vertex_index"))
      return "its '" + face.name + "' elements hold more than one list of vertex indices";
    const Property& list = face.properties[0];
    const Value count{0, 0, list.count}, item{0, 0, list.type};
    if (!count.is_integer() || !item.is_integer()) return "its '" + face.name + "' lists are not integers";
  }
  std::vector<std::string> names;
  for (const Property& p : h.elements[0].properties) {
    if (p.list) return "a vertex property is a list";
    static const char* const kOther[] = {"normal_x", "normal_y", "normal_z", "tx", "ty"};
    for (const char* other : kOther)
      if (p.name == other) return "a vertex property is named '" + p.name + "'";
    if (std::find(names.begin(), names.end(), p.name) != names.end()) return "a vertex property is named twice";
    names.push_back(p.name);
  }
  const auto has = [&](const char* n) { return std::find(names.begin(), names.end(), n) != names.end(); };
  if (!has("x") || !has("y") || !has("z")) return "its vertices lack x, y or z";
  const int normals = has("nx") + has("ny") + has("nz");
  if (normals != 0 && normals != 3) return "its vertices have some normal components, not all";
  const int u = has("u") + has("s") + has("texture_u") + has("texture_s");
  const int v = has("v") + has("t") + has("texture_v") + has("texture_t");
  if (u > 1 || v > 1 || u != v) return "its vertices' texture coordinates are not one (u, v) pair";
  return "";
}

}  // namespace ply
}  // namespace opsila
