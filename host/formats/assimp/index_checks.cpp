// Text formats whose faces index a vertex list that the importer's readers
// trust: a face of an ASE or DirectX .x mesh naming a vertex past the list
// was dropped or turned into a line, and an AC3D surface's reference past
// its object's vertices dropped it, each with exit 0 and a changed model
// (found by hand). So every index is checked first, naming its line.
// Binary .x files are left to the importer; binary 3DS's overflow is heard
// from the importer (import_warnings.cpp).
#include <algorithm>
#include <cstdint>
#include <string>
#include <string_view>

#include "core/errors.h"
#include "formats/assimp/model_checks.h"
#include "formats/common/model_words.h"

namespace opsila {

namespace {

using model_words::quote;

// The words of a text, each with its line; `blanks` separate words
// besides whitespace; with `comments`, '#' and "//" start a comment that
// runs to the line's end.
class Words {
 public:
  Words(const std::string& text, std::string_view blanks, bool comments)
      : text_(text), blanks_(blanks), comments_(comments) {}

  // The next word; false at the end.
  bool next(std::string_view& w) {
    for (;;) {
      while (at_ < text_.size() && blank(text_[at_])) line_ += text_[at_++] == '\n';
      if (at_ >= text_.size()) return false;
      if (!comments_ || !(text_[at_] == '#' || text_.compare(at_, 2, "//") == 0)) break;
      while (at_ < text_.size() && text_[at_] != '\n') ++at_;
    }
    const std::size_t start = at_;
    while (at_ < text_.size() && !blank(text_[at_])) ++at_;
    w = std::string_view(text_).substr(start, at_ - start);
    word_line_ = line_;
    return true;
  }
  long line() const { return word_line_; }

 private:
  bool blank(char c) const {
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || blanks_.find(c) != std::string_view::npos;
  }
  const std::string& text_;
  std::string_view blanks_;
  bool comments_;
  std::size_t at_ = 0;
  long line_ = 1, word_line_ = 1;
};

// A whole number of at most 18 digits, or -1.
std::int64_t index_of(std::string_view w) {
  if (w.empty() || w.size() > 18 || w.find_first_not_of("0123456789") != std::string_view::npos) return -1;
  std::int64_t n = 0;
  for (char c : w) n = n * 10 + (c - '0');
  return n;
}

[[noreturn]] void fail(const std::string& name, long line, const std::string& format, const std::string& what) {
  throw InputError(name + ":" + std::to_string(line) + ": " + format + " " + what);
}

// The word w an index below `count`, or the file is refused: "FORMAT
// <subject> 'w', past <limit> (indices 0 to count - 1)".
void check_index(const std::string& name, long line, const std::string& format, std::string_view w,
                 std::int64_t count, const std::string& subject, const std::string& limit) {
  const std::int64_t i = index_of(w);
  if (i >= 0 && i < count) return;
  if (i < 0) fail(name, line, format, subject + " " + quote(w) + ", which is not an index");
  fail(name, line, format, subject + " " + quote(w) + ", past " + limit +
                               (count > 0 ? " (indices 0 to " + std::to_string(count - 1) + ")" : ""));
}

// A count of items each written in at least `each` bytes: one the file
// cannot hold is refused (the importer allocated for it first, past 1 GiB).
void check_room(const std::string& name, long line, const std::string& format, const std::string& key,
                std::int64_t count, std::size_t file_bytes, std::size_t each) {
  if (count < 0 || std::uint64_t(count) <= file_bytes / each) return;
  fail(name, line, format, key + " " + std::to_string(count) + " is more than a file of " +
                               std::to_string(file_bytes) + " bytes can hold");
}

}  // namespace

// ASE: *MESH_NUMVERTEX N, then *MESH_FACE k: A: a B: b C: c, each of a, b,
// c below N (the importer dropped such a face).
void check_ase(const std::string& text, const std::string& name) {
  Words words(text, "", false);
  std::string_view w;
  std::int64_t vertices = -1;
  while (words.next(w)) {
    if (w == "*MESH_NUMVERTEX" || w == "*MESH_NUMFACES") {
      const std::string key(w);
      const std::int64_t n = words.next(w) ? index_of(w) : -1;
      check_room(name, words.line(), "ASE", key, n, text.size(), 16);  // "*MESH_VERTEX 0 0 0 0"
      if (key == "*MESH_NUMVERTEX") vertices = n;
    } else if (w == "*MESH_FACE" && vertices >= 0) {
      const long line = words.line();
      std::string_view face;
      if (!words.next(face)) return;
      for (const char* corner : {"A:", "B:", "C:"}) {
        if (!words.next(w) || w != corner || !words.next(w)) break;
        check_index(name, line, "ASE", w, vertices,
                    "*MESH_FACE " + std::string(face) + " corner " + std::string(corner, 1) + " names vertex",
                    "*MESH_NUMVERTEX " + std::to_string(vertices));
      }
    }
  }
}

// AC3D: in each OBJECT, numvert N, then per surface `mat m` (m below the
// MATERIAL lines before it) and `refs K` followed by K lines, each starting
// with a vertex index below N (the importer dropped such a surface).
void check_ac3d(const std::string& text, const std::string& name) {
  std::int64_t vertices = 0, materials = 0;
  std::size_t at = 0;
  long line = 0;
  std::int64_t refs_left = 0;
  while (at < text.size()) {
    std::size_t end = text.find('\n', at);
    if (end == std::string::npos) end = text.size();
    const std::string_view l = std::string_view(text).substr(at, end - at);
    at = end + 1;
    ++line;
    std::size_t k = 0;
    std::string_view key, value;
    if (!model_words::next_word(l, k, key)) continue;
    const bool has_value = model_words::next_word(l, k, value);
    if (refs_left > 0) {
      --refs_left;
      check_index(name, line, "AC3D", key, vertices, "surface reference names vertex",
                  "its OBJECT's numvert " + std::to_string(vertices));
      continue;
    }
    // Each vertex, reference or kid takes a line of at least 2 bytes.
    const std::int64_t n = has_value ? index_of(value) : -1;
    if (key == "numvert" || key == "numsurf" || key == "refs" || key == "kids")
      check_room(name, line, "AC3D", std::string(key), n, text.size(), 2);
    if (key == "MATERIAL") ++materials;
    else if (key == "OBJECT") vertices = 0;
    else if (key == "numvert") vertices = std::max<std::int64_t>(n, 0);
    else if (key == "refs") refs_left = std::max<std::int64_t>(n, 0);
    else if (key == "mat" && has_value)
      check_index(name, line, "AC3D", value, materials, "surface's mat names material",
                  "the " + std::to_string(materials) + " MATERIAL line(s) before it");
  }
}

// DirectX .x, text: each Mesh's vertex count, its vertices (three numbers
// each), its face count and faces (a corner count, then that many indices),
// every index below the vertex count (the importer turned such a face into
// a line). Separators (';', ',') are blanks; a Mesh not laid out so is
// left to the importer.
void check_x_text(const std::string& text, const std::string& name) {
  if (text.size() < 16 || text.compare(8, 4, "txt ") != 0) return;  // binary or compressed
  Words words(text, ";,", true);
  std::string_view w, previous;
  while (words.next(w)) {
    const bool mesh = w == "Mesh" && previous != "template";
    previous = w;
    if (!mesh) continue;
    while (words.next(w) && w != "{") {
    }
    if (!words.next(w)) return;
    const std::int64_t vertices = index_of(w);
    if (vertices < 0) continue;
    check_room(name, words.line(), "DirectX", "Mesh vertex count", vertices, text.size(), 6);  // "0;0;0;"
    for (std::int64_t v = 0; v < 3 * vertices; ++v)
      if (!words.next(w)) return;
    if (!words.next(w)) return;
    const std::int64_t faces = index_of(w);
    check_room(name, words.line(), "DirectX", "Mesh face count", faces, text.size(), 4);  // "1;0;"
    for (std::int64_t f = 0; f < faces; ++f) {
      if (!words.next(w)) return;
      const std::int64_t corners = index_of(w);
      for (std::int64_t c = 0; c < corners; ++c) {
        if (!words.next(w)) return;
        check_index(name, words.line(), "DirectX", w, vertices,
                    "Mesh face " + std::to_string(f + 1) + " of " + std::to_string(faces) + " names vertex",
                    "the Mesh's " + std::to_string(vertices) + " vertices");
      }
    }
  }
}

}  // namespace opsila
