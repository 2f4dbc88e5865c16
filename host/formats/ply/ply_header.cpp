// A PLY header, read by one parser for the stream (strictly) and for the
// checks before the importer (as the importer reads it), and whether the
// PLY stream reads the file exactly as the importer path does.
#include <algorithm>
#include <limits>
#include <sstream>
#include <string_view>

#include "core/errors.h"
#include "core/util.h"
#include "formats/common/model_files.h"
#include "formats/ply/ply_format.h"

namespace opsila {
namespace ply {

namespace {

// The header's end is looked for in the file's first 64 KiB.
constexpr std::size_t kMaxHeaderBytes = 64 * 1024;

Type type_named(const std::string& name) {
  static const std::pair<const char*, Type> kTypes[] = {
      {"char", Type::int8},     {"int8", Type::int8},       {"uchar", Type::uint8},    {"uint8", Type::uint8},
      {"short", Type::int16},   {"int16", Type::int16},     {"ushort", Type::uint16},  {"uint16", Type::uint16},
      {"int", Type::int32},     {"int32", Type::int32},     {"uint", Type::uint32},    {"uint32", Type::uint32},
      {"float", Type::float32}, {"float32", Type::float32}, {"double", Type::float64}, {"float64", Type::float64}};
  for (const auto& [n, type] : kTypes)
    if (name == n) return type;
  return Type::unknown;
}

bool all_digits(const std::string& w) { return !w.empty() && w.find_first_not_of("0123456789") == std::string::npos; }

[[noreturn]] void no_end(const std::string& path) {
  throw InputError(path + ": PLY header without an 'end_header' line (truncated or not PLY)");
}

// The lines between 'ply' and 'end_header', one at a time, into `h`. The
// stream's reading fails on the line at fault; the importer's lets be what
// the importer lets be and judges the rest after the header (ImporterJudge).
struct HeaderLines {
  const std::string& path;
  Header& h;
  const bool strict;
  int line = 0;
  bool format_seen = false;
  bool property_first = false;  // the importer's reading: a property before any element

  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(path + ":" + std::to_string(line) + ": PLY header: " + what);
  }
  Type type(const std::string& name) const {
    const Type t = type_named(name);
    if (strict && t == Type::unknown) fail("unknown property type '" + name.substr(0, 20) + "'");
    return t;
  }
  void element(std::istringstream& words) {
    std::string name, count, extra;
    words >> name >> count >> extra;
    if (!strict) {
      // The importer counts a word's leading digits ("5loat" is 5, found by
      // fuzz_model: read as 0 here, the checks walked the binary data from
      // another place than the importer, which allocated 8 GB). After a
      // name it does not know it reads the count from the name itself
      // ("element 5555555 x" is 5,555,555 elements, which it read for
      // ever; also found by fuzz_model), and a texture file has none.
      if (!importer_knows(name)) count = name == "TextureFile" ? "" : name;
      const std::string digits = count.substr(0, count.find_first_not_of("0123456789"));
      const std::uint64_t n = digits.empty()        ? 0
                              : digits.size() <= 19 ? std::stoull(digits)
                                                    : std::numeric_limits<std::uint64_t>::max();
      h.elements.push_back(Element{name, n, {}, line});
      return;
    }
    if (!format_seen) fail("an element before the format line");
    if (name.empty() || !extra.empty() || count.size() > 19 || !all_digits(count))
      fail("'element NAME COUNT' expected");
    for (const Element& e : h.elements)
      if (e.name == name) fail("the element '" + name.substr(0, 20) + "' is declared twice");
    h.elements.push_back(Element{name, std::stoull(count), {}, line});
  }
  void property(std::istringstream& words) {
    if (h.elements.empty()) {
      if (strict) fail("a property before any element");
      property_first = true;
      return;
    }
    std::string a, b, c, d, extra;
    words >> a >> b >> c >> d >> extra;
    Property p;
    if (a == "list") {
      if (strict && (d.empty() || !extra.empty())) fail("'property list COUNT_TYPE TYPE NAME' expected");
      p.list = true, p.count = type(b), p.type = type(c), p.name = d;
    } else {
      if (strict && (b.empty() || !c.empty())) fail("'property TYPE NAME' expected");
      p.type = type(a), p.name = b;
    }
    h.elements.back().properties.push_back(p);
  }
  void format(std::istringstream& words) {
    std::string f, version, extra;
    words >> f >> version >> extra;
    if (strict && (format_seen || version != "1.0" || !extra.empty())) fail("'format TYPE 1.0' expected once");
    // The importer's reading judges the first format line: a later one
    // must not stand in for a broken first (found by fuzz_model: a 4 GB
    // allocation inside the importer).
    if (format_seen) return;
    h.format_name = f;
    h.format_version = version;
    if (f == "ascii") h.format = Format::ascii;
    else if (f == "binary_little_endian") h.format = Format::little_endian;
    else if (f == "binary_big_endian") h.format = Format::big_endian;
    else if (strict) fail("format '" + f.substr(0, 20) + "' (ascii, binary_little_endian or binary_big_endian)");
    format_seen = true;
  }
  // One line; true at the stream's 'end_header' (the importer's end is
  // the line that starts with it, found before).
  bool read(const std::string& text) {
    std::istringstream words(text);
    std::string keyword;
    words >> keyword;
    if (keyword == "end_header") return strict;
    if (keyword == "comment" || keyword == "obj_info") {
      h.comments.push_back(text.substr(std::min(text.size(), text.find(keyword) + keyword.size())));
    } else if (keyword == "format") {
      format(words);
    } else if (keyword == "element") {
      element(words);
    } else if (keyword == "property") {
      property(words);
    } else if (strict) {
      fail(keyword.empty() ? "empty line" : "unknown line '" + keyword.substr(0, 20) + "'");
    }
    return false;
  }
};

// What the importer misreads in a header it reads (found by fuzz_model): it
// allocates what the element counts ask for before reading one, frees what
// it did not allocate when an element is declared twice, and reads binary
// data out of bounds with unknown types and formats. In the order the
// checks before the importer always gave them.
void judge_for_importer(const Header& h, const HeaderLines& lines, const std::string& path) {
  if (lines.property_first) throw InputError(path + ": PLY header has a property before any element");
  for (std::size_t k = 0; k < h.elements.size(); ++k) {
    const Element& e = h.elements[k];
    for (std::size_t j = 0; j < k; ++j)
      if (h.elements[j].name == e.name)
        throw InputError(path + ": PLY header declares the element '" + e.name.substr(0, 20) + "' twice");
    const std::uint64_t per = std::max<std::size_t>(1, e.properties.size());
    if (e.count > h.file_bytes / per)
      throw InputError(path + ": PLY header asks for " + std::to_string(e.count) + " '" + e.name +
                       "' elements, more than a file of " + std::to_string(h.file_bytes) + " bytes can hold");
  }
}

void judge_types_for_importer(const Header& h, const std::string& path) {
  for (const Element& e : h.elements)
    for (const Property& p : e.properties)
      if (p.type == Type::unknown || (p.list && p.count == Type::unknown))
        throw InputError(path + ": PLY '" + e.name.substr(0, 20) + "' element: a property of unknown type");
      else if (p.list && (p.count == Type::float32 || p.count == Type::float64))
        throw InputError(path + ": PLY '" + e.name.substr(0, 20) + "' element: the list '" + p.name.substr(0, 20) +
                         "' has a count type that is not an integer type");
  if (h.format_name != "ascii" && h.format_name != "binary_little_endian" && h.format_name != "binary_big_endian")
    throw InputError(path + ": PLY format '" + h.format_name.substr(0, 20) +
                     "' (ascii, binary_little_endian or binary_big_endian)");
  // The only version there is: another may lay its body out otherwise.
  if (h.format_version != "1.0")
    throw InputError(path + ": PLY format version '" + h.format_version.substr(0, 20) + "' (1.0 expected)");
}

// Where the importer's header ends: the start of the first line that
// starts with 'end_header' (a line of its own: the importer misreads one
// that ends another line).
std::size_t importer_end(std::string_view bytes, const std::string& path) {
  const std::size_t end = bytes.find("\nend_header");
  if (end == std::string_view::npos || end > kMaxHeaderBytes) no_end(path);
  return end + 1;
}

// The importer's body starts after 'end_header' and its line break.
std::size_t importer_body(std::string_view bytes, std::size_t end, const std::string& path) {
  std::size_t data = end + 10;
  if (bytes.compare(data, 2, "\r\n") == 0) ++data;
  if (data >= bytes.size() || bytes[data] != '\n')
    throw InputError(path + ": PLY 'end_header' not followed by a line break");
  return data + 1;
}

}  // namespace

bool fits_type(std::int64_t v, Type t) {
  switch (t) {
    case Type::int8: return v >= -128 && v <= 127;
    case Type::uint8: return v >= 0 && v <= 255;
    case Type::int16: return v >= -32768 && v <= 32767;
    case Type::uint16: return v >= 0 && v <= 65535;
    case Type::int32: return v >= -2147483648LL && v <= 2147483647LL;
    case Type::uint32: return v >= 0 && v <= 4294967295LL;
    default: return false;
  }
}

int type_bytes(Type t) {
  switch (t) {
    case Type::int8: case Type::uint8: return 1;
    case Type::int16: case Type::uint16: return 2;
    case Type::int32: case Type::uint32: case Type::float32: return 4;
    case Type::float64: return 8;
    default: return 0;
  }
}

Header parse_header(const std::string& bytes, std::uint64_t file_bytes, const std::string& path, Reading how) {
  const bool importer = how == Reading::importer;
  Header h;
  h.file_bytes = file_bytes;
  const std::string_view head = std::string_view(bytes).substr(0, importer ? bytes.size() : kMaxHeaderBytes);
  std::size_t at = 0;
  // The next line, without its line break; false where none ends.
  const auto next_line = [&](std::string& text) {
    const std::size_t nl = head.find('\n', at);
    if (nl == std::string_view::npos) return false;
    text = std::string(head.substr(at, nl - at));
    if (!text.empty() && text.back() == '\r') text.pop_back();
    at = nl + 1;
    return true;
  };
  // The 'ply' line (the importer would take "PLY" in any case, so it comes first).
  std::string text;
  const bool first = next_line(text);
  if (head.rfind("ply\r", 0) == 0 && (!first || text != "ply"))
    throw InputError(path + ": its lines end with a lone CR (old Mac text): PLY lines end with LF or CR LF");
  if (!first && !importer) no_end(path);
  if (!first || text != "ply") throw InputError(path + ": not PLY (a PLY file starts with the line 'ply')");
  const std::size_t end = importer ? importer_end(head, path) : std::string::npos;
  HeaderLines lines{path, h, !importer, 1};
  while (at != end) {
    ++lines.line;
    if (!next_line(text)) no_end(path);
    if (lines.read(text)) break;
  }
  if (importer) {
    judge_for_importer(h, lines, path);
    at = importer_body(head, end, path);
    judge_types_for_importer(h, path);
    h.lines = static_cast<int>(std::count(head.begin(), head.begin() + std::ptrdiff_t(at), '\n'));
  } else {
    if (!lines.format_seen) lines.fail("no format line");
    h.lines = lines.line;
  }
  // A property named twice: the importer reads one of them, and says
  // "no facets" when it is the face list.
  for (const Element& e : h.elements)
    for (std::size_t k = 0; k < e.properties.size(); ++k)
      for (std::size_t j = 0; j < k; ++j)
        if (e.properties[j].name == e.properties[k].name)
          throw InputError(path + ": PLY '" + e.name.substr(0, 20) + "' element: the property '" +
                           e.properties[k].name.substr(0, 20) + "' is declared twice");
  // Both readers would take a face's corner 3.99 as vertex 3.
  for (const Element& e : h.elements)
    for (const Property& p : e.properties)
      if (p.list && (p.type == Type::float32 || p.type == Type::float64) && e.name == "face" &&
          (p.name == "vertex_indices" || p.name == "vertex_index"))
        throw InputError(path + ": PLY 'face' element: the list '" + p.name +
                         "' holds floating-point values, where vertex indices are integers");
  h.body = at;
  return h;
}

Header read_header(const std::string& path, const std::string* bytes) {
  if (bytes) return parse_header(bytes->substr(0, kMaxHeaderBytes), bytes->size(), path, Reading::stream);
  ModelFiles files;
  const std::uint64_t size = files.size(path);
  return parse_header(files.head(path, kMaxHeaderBytes), size, path, Reading::stream);
}

bool importer_knows(const std::string& element) {
  static const char* const kKnown[] = {"vertex", "face", "tristrips", "edge", "material"};
  for (const char* k : kKnown)
    if (element == k) return true;
  return false;
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
