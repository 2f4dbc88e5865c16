// What an STL file is (stl_format.h): its shape, the checks before the
// importer reads it, and the check of the importer's scene of it.
#include <algorithm>
#include <cctype>
#include <string_view>

#include "core/errors.h"
#include "formats/common/model_words.h"
#include "formats/stl/stl_format.h"

#ifdef OPSILA_HAVE_ASSIMP
#include <assimp/scene.h>
#endif

namespace opsila {
namespace stl {

using namespace model_words;

namespace {

// The text keywords, which the importer reads in lower case only.
constexpr std::string_view kKeywords[] = {"solid", "facet", "normal", "outer", "loop", "vertex",
                                          "endloop", "endfacet", "endsolid"};

// w in lower case where it is a keyword in any case, else "".
std::string lower_keyword(std::string_view w) {
  std::string low(w);
  for (char& c : low) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  for (std::string_view k : kKeywords)
    if (low == k) return low;
  return "";
}

// A text file: every facet ends ("endfacet") and so does the last solid;
// the three values after 'vertex' and after 'normal' are numbers as the
// importer reads them (its own message names no line). A solid's name, the
// rest of its line, may hold any word.
void check_text(const std::string& bytes, const std::string& name) {
  std::size_t at = 0, counted = 0;
  unsigned long long line = 1;
  const auto line_at = [&](std::size_t pos) {
    line += std::count(bytes.begin() + std::ptrdiff_t(counted), bytes.begin() + std::ptrdiff_t(pos), '\n');
    counted = pos;
    return line;
  };
  std::string_view w;
  unsigned long long facets = 0;
  int corners = 0;  // the facet's 'vertex' lines so far: the importer kept 3 and dropped a 4th unsaid
  bool in_facet = false, in_solid = false;
  const auto corners_wrong = [&](const std::string& what) {
    throw InputError(name + ":" + std::to_string(line_at(at - w.size())) + ": STL facet " + std::to_string(facets) +
                     " " + what + " (a facet is a triangle: 3 'vertex' lines)");
  };
  const auto misplaced = [&](const std::string& what) {
    throw InputError(name + ":" + std::to_string(line_at(at - w.size())) + ": STL " + quote(w) + " " + what +
                     " (the importer dropped it without a word)");
  };
  while (next_word(bytes, at, w)) {
    if (const std::string low = lower_keyword(w); !low.empty() && low != w)
      throw InputError(name + ":" + std::to_string(line_at(at - w.size())) + ": STL keyword " + quote(w) +
                       " is not in lower case: the importer reads '" + low + "' only");
    if (!in_solid && w != "solid") misplaced("after 'endsolid', outside any solid");
    if (w == "vertex" && !in_facet) misplaced("outside a facet");
    if (w == "solid" || w == "endsolid") {
      in_solid = w == "solid";
      at = std::min(bytes.find('\n', at), bytes.size());
    } else if (w == "facet") {
      in_facet = true, ++facets, corners = 0;
    } else if (w == "endfacet") {
      if (corners < 3) corners_wrong("has " + std::to_string(corners) + " 'vertex' lines");
      in_facet = false;
    } else if (w == "vertex" || w == "normal") {
      const std::string key(w);
      if (key == "vertex" && ++corners > 3) corners_wrong("has a 4th 'vertex'");
      for (int k = 0; k < 3; ++k) {
        if (!next_word(bytes, at, w)) break;  // the end of the data: said below
        if (whole_number(w)) {
          // Every vertex of a text STL is a facet's.
          if (key == "vertex" && !finite_in_float(w))
            throw InputError(name + ":" + std::to_string(line_at(at - w.size())) + ": STL 'vertex': " + quote(w) +
                             " is not a finite number");
          continue;
        }
        throw InputError(name + ":" + std::to_string(line_at(at - w.size())) + ": STL '" + key +
                         "' needs 3 numbers; " + quote(w) + " is not one");
      }
      // A 4th number was ignored by the importer, unsaid.
      std::size_t past = at;
      if (next_word(bytes, past, w) && whole_number(w))
        throw InputError(name + ":" + std::to_string(line_at(past - w.size())) + ": STL '" + key +
                         "' holds more than 3 numbers (" + quote(w) + " is a 4th)");
    }
  }
  if (in_facet)
    throw InputError(name + ": STL data ends inside facet " + std::to_string(facets) +
                     " (no 'endfacet': truncated file)");
  if (in_solid)
    throw InputError(name + ": STL data ends after facet " + std::to_string(facets) +
                     " without 'endsolid' (truncated file)");
}

// Why a binary STL's size does not match its header's facet count.
std::string size_mismatch(const Shape& s) {
  return "its size, " + std::to_string(s.size) + " bytes, is not 84 + 50 x the " + std::to_string(s.facets) +
         " facets its header counts";
}

}  // namespace

Shape shape_of(const std::string& head, std::uint64_t size) {
  Shape s;
  s.size = size;
  if (size >= kHeaderBytes && head.size() >= kHeaderBytes)
    for (int b = 3; b >= 0; --b) s.facets = s.facets << 8 | static_cast<unsigned char>(head[80 + b]);
  s.exact = size >= kHeaderBytes && size == kHeaderBytes + kRecordBytes * s.facets;
  std::size_t start = 0;
  while (start < head.size() && std::isspace(static_cast<unsigned char>(head[start]))) ++start;
  s.solid = head.compare(start, 5, "solid") == 0;
  s.solid_cased =
      !s.solid && head.size() >= start + 5 && lower_keyword(std::string_view(head).substr(start, 5)) == "solid";
  // A name is looked for wherever it starts in the 80 bytes.
  const std::string_view header = std::string_view(head).substr(0, kShapeBytes);
  for (const char* colours : {"COLOR=", "MATERIAL="}) {
    const std::size_t at = header.find(colours);
    if (s.colours.empty() && at != std::string_view::npos && at < 80) s.colours = colours;
  }
  return s;
}

std::string stream_refusal(const Shape& s) {
  if (s.size < kHeaderBytes) return "it is shorter than a binary STL's 84-byte header";
  if (!s.exact) {
    if (s.solid) return "an ASCII STL";
    return size_mismatch(s);
  }
  if (s.facets == 0) return "its header counts no facets";
  if (!s.colours.empty()) return "its header names Materialise colours (" + s.colours + ")";
  return "";
}

void check_stl(const std::string& bytes, const std::string& name) {
  const Shape s = shape_of(bytes, bytes.size());
  // UTF-16 text had been read as a binary STL of two million facets.
  const std::string_view start = std::string_view(bytes).substr(0, 10);
  if (start.rfind("\xff\xfe", 0) == 0 || start.rfind("\xfe\xff", 0) == 0 ||
      start == std::string_view("s\0o\0l\0i\0d\0", 10) || start == std::string_view("\0s\0o\0l\0i\0d", 10))
    throw InputError(name + ": UTF-16 text: a text STL is ASCII (save it as such)");
  // Text never holds a NUL; a binary header may start with "solid".
  if ((s.text() || (s.solid_cased && !s.exact)) && bytes.find('\0') == std::string::npos)
    return check_text(bytes, name);
  if (s.size < kHeaderBytes) throw InputError(name + ": binary STL shorter than its 84-byte header (truncated file)");
  if (kHeaderBytes + kRecordBytes * s.facets > s.size)
    throw InputError(name + ": binary STL header counts " + std::to_string(s.facets) + " facets; the file holds " +
                     std::to_string((s.size - kHeaderBytes) / kRecordBytes) + " (truncated file)");
  if (!s.exact) throw InputError(name + ": binary STL: " + size_mismatch(s) + " (data past its facets)");
}

#ifdef OPSILA_HAVE_ASSIMP
void check_imported_scene(const aiScene& ai, const std::string& name) {
  const auto bad = [&](const std::string& what) {
    throw InputError(name + ": the STL reader's scene is inconsistent (" + what + ")");
  };
  if (!ai.mRootNode || (ai.mNumMeshes > 0 && !ai.mMeshes)) bad("no root node or mesh list");
  for (unsigned m = 0; m < ai.mNumMeshes; ++m) {
    const aiMesh* mesh = ai.mMeshes[m];
    if (!mesh) bad("mesh " + std::to_string(m) + " missing");
    if ((mesh->mNumVertices > 0 && !mesh->mVertices) || (mesh->mNumFaces > 0 && !mesh->mFaces))
      bad("mesh " + std::to_string(m) + " without its arrays");
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices > 0 && !face.mIndices) bad("a face without indices");
      for (unsigned k = 0; k < face.mNumIndices; ++k)
        if (face.mIndices[k] >= mesh->mNumVertices) bad("a vertex index out of range");
    }
  }
  for (unsigned k = 0; k < ai.mNumMaterials; ++k)
    if (!ai.mMaterials || !ai.mMaterials[k]) bad("a material missing");
}
#endif

}  // namespace stl
}  // namespace opsila
