// PLY and STL checks (OFF's are in off_checks.cpp, glTF's in gltf_checks.cpp).
#include "formats/assimp/model_checks.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "core/util.h"
#include "formats/obj/obj_loader.h"
#include "formats/common/model_words.h"
#include "formats/obj/obj_text.h"

namespace opsila {

using namespace model_words;

namespace {

struct PlyProperty {
  int count_bytes = 0;  // > 0 for a list: the size of its count
  int item_bytes = 0;   // size of the value (or of each list item)
  std::string name;
};
struct PlyElement {
  std::string name;
  unsigned long long count = 0;
  std::vector<PlyProperty> properties;
};

// Bytes of a PLY scalar type, 0 for an unknown one (the importer judges it).
int ply_type_bytes(const std::string& t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "int" || t == "uint" || t == "float" || t == "int32" || t == "uint32" || t == "float32") return 4;
  if (t == "double" || t == "float64") return 8;
  return 0;
}

[[noreturn]] void ply_truncated(const std::string& name, const PlyElement& e, unsigned long long i) {
  throw InputError(name + ": PLY data ends early: '" + e.name + "' element " + std::to_string(i + 1) + " of " +
                   std::to_string(e.count) + " is missing or incomplete (truncated file)");
}

// The text data: every property one word, a list its count and that many.
// A vertex whose x, y or z is not finite in floats (as the importer stores
// it) is named with its line where a face uses it (data starts on line
// `first_line`); one no face uses is harmless.
void check_ply_text(std::string_view data, unsigned long long first_line, const std::vector<PlyElement>& elements,
                    const std::string& name) {
  std::size_t at = 0, counted = 0;
  unsigned long long line = first_line;
  const auto line_of = [&](std::string_view word) {  // words in file order
    const std::size_t pos = std::size_t(word.data() - data.data());
    line += std::count(data.begin() + std::ptrdiff_t(counted), data.begin() + std::ptrdiff_t(pos), '\n');
    counted = pos;
    return line;
  };
  std::unordered_map<unsigned long long, unsigned long long> not_finite;  // vertex -> its line
  std::string_view w;
  for (const PlyElement& e : elements) {
    if (e.properties.empty()) continue;
    for (unsigned long long i = 0; i < e.count; ++i)
      for (const PlyProperty& p : e.properties) {
        if (!next_word(data, at, w)) ply_truncated(name, e, i);
        if (p.count_bytes == 0) {
          if (e.name == "vertex" && (p.name == "x" || p.name == "y" || p.name == "z") && !finite_in_float(w))
            not_finite.emplace(i, line_of(w));
          continue;
        }
        unsigned long long n = 0;
        if (w.size() > 19 || w.find_first_not_of("0123456789") != std::string_view::npos)
          throw InputError(name + ": PLY '" + e.name + "' element " + std::to_string(i + 1) + ": list length '" +
                           std::string(w.substr(0, 20)) + "' is not a count");
        for (char c : w) n = n * 10 + unsigned(c - '0');
        const bool corners = !not_finite.empty() && e.name == "face" &&
                             (p.name == "vertex_indices" || p.name == "vertex_index");
        for (unsigned long long k = 0; k < n; ++k) {
          if (!next_word(data, at, w)) ply_truncated(name, e, i);
          if (!corners || w.size() > 19 || w.find_first_not_of("0123456789") != std::string_view::npos) continue;
          const auto bad = not_finite.find(std::stoull(std::string(w)));
          if (bad != not_finite.end())
            throw InputError(name + ":" + std::to_string(line_of(w)) + ": PLY 'face' element " +
                             std::to_string(i + 1) + " of " + std::to_string(e.count) + ": vertex " + std::string(w) +
                             " (line " + std::to_string(bad->second) + ") is not a finite number");
        }
      }
  }
}

// The binary data: fixed sizes, lists read for their counts.
void check_ply_binary(std::string_view data, const std::vector<PlyElement>& elements, bool big_endian,
                      const std::string& name) {
  std::uint64_t at = 0;
  const std::uint64_t size = data.size();
  for (const PlyElement& e : elements) {
    bool lists = false;
    std::uint64_t fixed = 0;
    for (const PlyProperty& p : e.properties) lists = lists || p.count_bytes > 0, fixed += p.item_bytes;
    if (!lists) {  // count <= file size (check_ply_header), so no overflow
      if (fixed > 0 && e.count > (size - at) / fixed) ply_truncated(name, e, (size - at) / fixed);
      at += e.count * fixed;
      continue;
    }
    for (unsigned long long i = 0; i < e.count; ++i)
      for (const PlyProperty& p : e.properties) {
        std::uint64_t n = 1;
        if (p.count_bytes > 0) {
          if (std::uint64_t(p.count_bytes) > size - at) ply_truncated(name, e, i);
          n = 0;
          for (int b = 0; b < p.count_bytes; ++b) {
            const int k = big_endian ? b : p.count_bytes - 1 - b;
            n = n << 8 | static_cast<unsigned char>(data[at + k]);
          }
          at += p.count_bytes;
        }
        if (n > (size - at) / std::max(1, p.item_bytes)) ply_truncated(name, e, i);
        at += n * p.item_bytes;
      }
  }
}

// The importer's PLY reader does not stop on a header that never ends (found
// by fuzz_model), allocates what the element counts ask for before reading
// one, and renders a file that holds fewer elements than its header counts.
void check_ply_header(const std::string& head, std::size_t file_bytes, const std::string& name,
                      std::vector<PlyElement>& elements, std::string& format) {
  std::istringstream lines(head);
  std::string line;
  auto judge = [&] {
    if (elements.empty()) return;
    const PlyElement& e = elements.back();
    const unsigned long long per = std::max<std::size_t>(1, e.properties.size());
    if (e.count > file_bytes / per)
      throw InputError(name + ": PLY header asks for " + std::to_string(e.count) + " '" + e.name +
                       "' elements, more than a file of " + std::to_string(file_bytes) + " bytes can hold");
  };
  while (std::getline(lines, line)) {
    std::istringstream words(line);
    std::string keyword, a, b, c, d;
    words >> keyword >> a >> b >> c >> d;
    if (keyword == "format") {
      format = a;
    } else if (keyword == "element") {
      judge();
      // Two elements of one name: the importer frees what it did not
      // allocate on such a header (fuzz_model).
      for (const PlyElement& e : elements)
        if (e.name == a)
          throw InputError(name + ": PLY header declares the element '" + a.substr(0, 20) + "' twice");
      elements.push_back(PlyElement{a, 0, {}});
      if (!b.empty() && b.find_first_not_of("0123456789") == std::string::npos)  // else the importer judges
        elements.back().count = b.size() <= 19 ? std::stoull(b) : std::numeric_limits<unsigned long long>::max();
    } else if (keyword == "property" && elements.empty()) {
      throw InputError(name + ": PLY header has a property before any element");
    } else if (keyword == "property") {
      elements.back().properties.push_back(
          a == "list" ? PlyProperty{ply_type_bytes(b) > 0 ? ply_type_bytes(b) : -1, ply_type_bytes(c), d}
                      : PlyProperty{0, ply_type_bytes(a), b});
    }
  }
  judge();
}

}  // namespace

void check_ply(const std::string& bytes, const std::string& name) {
  // The importer takes "PLY" in any case, and then lines it does not know.
  if (bytes.compare(0, 4, "ply\n") != 0 && bytes.compare(0, 5, "ply\r\n") != 0)
    throw InputError(name + ": not PLY (a PLY file starts with the line 'ply')");
  // A line of its own (the importer misreads one that ends another line).
  std::size_t end = bytes.find("\nend_header");
  if (end == std::string::npos || end > 64 * 1024)
    throw InputError(name + ": PLY header without an 'end_header' line (truncated or not PLY)");
  ++end;
  std::vector<PlyElement> elements;
  std::string format;
  check_ply_header(bytes.substr(0, end), bytes.size(), name, elements, format);
  std::size_t data = end + 10;
  if (bytes.compare(data, 2, "\r\n") == 0) ++data;
  if (data >= bytes.size() || bytes[data] != '\n')
    throw InputError(name + ": PLY 'end_header' not followed by a line break");
  ++data;
  // Unknown types and formats: the importer reads binary data out of
  // bounds with them (fuzz_model).
  for (const PlyElement& e : elements)
    for (const PlyProperty& p : e.properties)
      if (p.item_bytes == 0 || p.count_bytes < 0)
        throw InputError(name + ": PLY '" + e.name.substr(0, 20) + "' element: a property of unknown type");
  if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian")
    throw InputError(name + ": PLY format '" + format.substr(0, 20) +
                     "' (ascii, binary_little_endian or binary_big_endian)");
  const std::string_view body = std::string_view(bytes).substr(data);
  if (format == "ascii")
    check_ply_text(body, 1 + std::count(bytes.begin(), bytes.begin() + std::ptrdiff_t(data), '\n'), elements, name);
  else check_ply_binary(body, elements, format == "binary_big_endian", name);
  // Points only: the importer's validation would refuse its empty mesh
  // ("Mesh contains no faces"). Its readers take faces from these elements.
  bool faces = false;
  for (const PlyElement& e : elements) {
    const std::string n = lower(e.name);
    faces = faces || (e.count > 0 && (n.rfind("face", 0) == 0 || n.rfind("tristrips", 0) == 0 ||
                                      n.rfind("range_grid", 0) == 0));
  }
  if (!faces)
    throw InputError(name + ": no facets (the PLY file has no faces: no 'face' element with entries, points only)");
}

// Binary STL: 80 bytes of header, a 32-bit facet count, 50 bytes a facet.
// The importer takes a file whose size is exactly that as binary even when
// it starts with "solid", as here; anything else starting so is text.
void check_stl(const std::string& bytes, const std::string& name) {
  const std::uint64_t size = bytes.size();
  std::uint64_t count = 0;
  if (size >= 84)
    for (int b = 3; b >= 0; --b) count = count << 8 | static_cast<unsigned char>(bytes[80 + b]);
  std::size_t start = 0;
  while (start < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[start]))) ++start;
  const bool text = bytes.compare(start, 5, "solid") == 0 && !(size >= 84 && 84 + 50 * count == size);
  if (!text) {
    if (size < 84) throw InputError(name + ": binary STL shorter than its 84-byte header (truncated file)");
    if (84 + 50 * count > size)
      throw InputError(name + ": binary STL header counts " + std::to_string(count) + " facets; the file holds " +
                       std::to_string((size - 84) / 50) + " (truncated file)");
    return;
  }
  // Text: every facet ends ("endfacet") and so does the last solid; the
  // three values after 'vertex' and after 'normal' are numbers as the
  // importer reads them (its own message names no line). A solid's name,
  // the rest of its line, may hold any word.
  std::size_t at = 0, counted = 0;
  unsigned long long line = 1;
  const auto line_at = [&](std::size_t pos) {
    line += std::count(bytes.begin() + std::ptrdiff_t(counted), bytes.begin() + std::ptrdiff_t(pos), '\n');
    counted = pos;
    return line;
  };
  std::string_view w;
  unsigned long long facets = 0;
  bool in_facet = false, in_solid = false;
  while (next_word(bytes, at, w)) {
    if (w == "solid" || w == "endsolid") {
      in_solid = w == "solid";
      at = std::min(bytes.find('\n', at), bytes.size());
    } else if (w == "facet") {
      in_facet = true, ++facets;
    } else if (w == "endfacet") {
      in_facet = false;
    } else if (w == "vertex" || w == "normal") {
      const std::string key(w);
      for (int k = 0; k < 3; ++k) {
        if (!next_word(bytes, at, w)) break;  // the end of the data: said below
        if (number_start(w)) {
          // Every vertex of a text STL is a facet's.
          if (key == "vertex" && !finite_in_float(w))
            throw InputError(name + ":" + std::to_string(line_at(at - w.size())) + ": STL 'vertex': " +
                             obj_text::quote(w) + " is not a finite number");
          continue;
        }
        throw InputError(name + ":" + std::to_string(line_at(at - w.size())) + ": STL '" + key +
                         "' needs 3 numbers; " + obj_text::quote(w) + " is not one");
      }
    }
  }
  if (in_facet)
    throw InputError(name + ": STL data ends inside facet " + std::to_string(facets) +
                     " (no 'endfacet': truncated file)");
  if (in_solid)
    throw InputError(name + ": STL data ends after facet " + std::to_string(facets) +
                     " without 'endsolid' (truncated file)");
}

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

void check_model_file_shape(ModelFiles& files, const std::string& path, const std::string& ext) {
  const std::string e = lower(!ext.empty() && ext[0] == '.' ? ext.substr(1) : ext);
  if (e == "off") {
    const std::uint64_t size = files.size(path);
    check_off(files.head(path, kMaxInputFileBytes), static_cast<std::size_t>(size), path);
    return;
  }
  const std::string bytes = files.head(path, kMaxInputFileBytes);
  if (e == "ply") check_ply(bytes, path);
  else if (e == "stl") check_stl(bytes, path);
  else if (e == "gltf" || e == "glb") check_gltf(files, bytes, path);
  else check_nesting(bytes, path);
}

}  // namespace opsila
