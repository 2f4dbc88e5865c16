// OFF, checked as the importer's OFF reader reads it, which is lenient in
// ways that change the model without a word: an index beyond the vertices
// becomes the last vertex, a face of 0 or of more than 9 vertices is
// dropped, a count or index that is not digits reads as 0, a line of 4096
// characters or more is split (and overruns its line buffer by one byte),
// and its own errors name no line. It also allocates what the header's
// counts ask for before reading a vertex (found by fuzz_model: tens of GB
// from a 100-byte file). Every such file is refused here, naming its line.
//
// The layout: a header of optional prefixes (ST, C, N, 4, n) and the keyword
// OFF, the dimension after an 'n' prefix, then the vertex, face and edge
// counts, with comment lines and blank space anywhere between; then one line
// per vertex (its coordinates first) and one per face ("n i1 ... in").
#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>
#include <string_view>
#include <unordered_map>

#include "core/errors.h"
#include "formats/assimp/model_checks.h"
#include "formats/common/model_words.h"
#include "formats/obj/obj_text.h"

namespace opsila {

using namespace model_words;

namespace {

constexpr const char* kCommentLine = ": a comment line (the model importer reads comments in the header only)";

class OffCheck {
 public:
  OffCheck(const std::string& text, std::size_t file_bytes, const std::string& name)
      : t_(text), file_bytes_(file_bytes), name_(name) {}

  void run() {
    if (t_.find('\0') != std::string_view::npos) {
      advance_to(t_.find('\0'));
      throw InputError(where() + "OFF text holds a NUL byte (not an OFF file)");
    }
    header();
    vertices();
    faces();
    rest();
  }

 private:
  std::string where() const { return name_ + ":" + std::to_string(line_) + ": "; }
  void advance_to(std::size_t to) {
    line_ += std::count(t_.begin() + std::ptrdiff_t(at_), t_.begin() + std::ptrdiff_t(to), '\n');
    at_ = to;
  }
  // The header's tokens: blank space, line ends and comment lines skipped.
  void next_token() {
    std::size_t i = at_;
    for (;;) {
      while (i < t_.size() && std::isspace(static_cast<unsigned char>(t_[i]))) ++i;
      if (i >= t_.size() || t_[i] != '#') break;
      while (i < t_.size() && t_[i] != '\n') ++i;
    }
    advance_to(i);
  }
  std::size_t digits_at(std::size_t i) const {
    std::size_t j = i;
    while (j < t_.size() && t_[j] >= '0' && t_[j] <= '9') ++j;
    return j - i;
  }
  bool prefix(std::string_view p) {
    if (t_.compare(at_, p.size(), p) != 0) return false;
    at_ += p.size();
    return true;
  }

  void header() {
    next_token();
    prefix("ST"), prefix("C");
    normals_ = prefix("N");
    homogeneous_ = prefix("4");
    const bool dimension = prefix("n"), keyword = prefix("OFF");
    next_token();
    if (!keyword && digits_at(at_) == 0) throw InputError(where() + "not OFF (no 'OFF' keyword and no vertex count)");
    // Without the keyword the importer still takes a leading 4 for the
    // "4OFF" prefix, and reads the counts one place late.
    if (!keyword && homogeneous_)
      throw InputError(where() + "OFF without its 'OFF' keyword, and its vertex count starts with 4, which the "
                                 "model importer reads as the '4OFF' prefix: start the file with a line 'OFF'");
    if (!keyword) homogeneous_ = false;  // the importer's reading without the keyword
    const std::size_t d = digits_at(at_);
    if (dimension) {
      if (d == 0 || d > 1 || t_[at_] == '0' || t_[at_] > '3')
        throw InputError(where() + "OFF dimension " + obj_text::quote(t_.substr(at_, std::max<std::size_t>(d, 1))) +
                         " (1, 2 or 3 coordinates a vertex)");
      dims_ = unsigned(t_[at_] - '0');
      at_ += d;
      next_token();
    }
    if (!keyword) dims_ = 3;
    if (keyword && prefix("BINARY"))
      throw InputError(where() + "binary OFF ('OFF BINARY'): the model importer reads text OFF only");
    counts();
  }

  // The vertex, face and edge counts.
  void counts() {
    unsigned long long lines[3] = {0, 0, 0};
    const char* const what[3] = {"vertex", "face", "edge"};
    for (int k = 0; k < 3; ++k) {
      lines[k] = line_;
      // Without an edge count the importer takes the first digits of the
      // first vertex for it, and misreads every vertex after.
      if (k == 2 && lines[0] == lines[1] && line_ != lines[1])
        throw InputError(name_ + ":" + std::to_string(lines[1]) +
                         ": OFF header has vertex and face counts but no edge count ('vertices faces edges')");
      const std::size_t d = digits_at(at_);
      if (d == 0)
        throw InputError(
            where() + "OFF header: the " + what[k] + " count " +
            obj_text::quote(t_.substr(at_, std::min<std::size_t>(t_.find_first_of(" \t\r\n", at_), t_.size()) - at_)) +
            " is not a number");
      const std::string digits(t_.substr(at_, d));
      if (k < 2 && (d > 15 || std::stoull(digits) > file_bytes_ / 2))
        throw InputError(name_ + ": OFF header asks for " + (d > 15 ? digits.substr(0, 15) + "..." : digits) + " " +
                         (k == 0 ? "vertices" : "faces") + ", more than a file of " + std::to_string(file_bytes_) +
                         " bytes can hold");
      if (k < 2) counts_[k] = std::stoull(digits);
      at_ += d;
      next_token();
    }
    if (counts_[0] == 0) throw InputError(where() + "OFF header counts no vertices");
    if (counts_[1] == 0) throw InputError(where() + "OFF header counts no faces");
  }

  // The body's lines: blank lines skipped, comment lines not (the importer
  // reads a vertex or face from them and fails or misreads).
  bool next_line() {
    std::size_t i = at_;
    while (i < t_.size() && (t_[i] == '\n' || t_[i] == '\r' || t_[i] == '\f')) ++i;
    advance_to(i);
    if (at_ >= t_.size()) return false;
    const std::size_t end = std::min(t_.find_first_of("\n\r\f", at_), t_.size());
    l_ = t_.substr(at_, end - at_);
    if (l_.size() >= 4096)
      throw InputError(where() + "OFF line of " + std::to_string(l_.size()) +
                       " characters (the model importer reads at most 4095)");
    at_ = end;
    return true;
  }
  bool comment_line() const {
    const std::size_t first = l_.find_first_not_of(" \t");
    return first != std::string_view::npos && l_[first] == '#';
  }

  // Vertices that are not finite as the importer reads them (in floats,
  // divided by w): the line of each, named if a face uses it.
  void vertices() {
    const std::size_t numbers = dims_ + (homogeneous_ ? 1 : 0) + (normals_ ? 3 : 0);
    for (unsigned long long v = 0; v < counts_[0]; ++v) {
      if (!next_line())
        throw InputError(name_ + ": OFF data ends after vertex " + std::to_string(v) + " of " +
                         std::to_string(counts_[0]) + " (truncated file)");
      const std::string vertex = "OFF vertex " + std::to_string(v + 1);
      if (comment_line()) throw InputError(where() + vertex + kCommentLine);
      std::size_t w_at = 0;
      std::string_view w;
      float c[4] = {0, 0, 0, 1};  // read only with a w
      bool finite = true;
      for (std::size_t k = 0; k < numbers; ++k) {
        if (!next_word(l_, w_at, w))
          throw InputError(where() + vertex + " needs " + std::to_string(numbers) + " numbers; the line has " +
                           std::to_string(k));
        if (!whole_number(w)) throw InputError(where() + vertex + ": " + obj_text::quote(w) + " is not a number");
        if (homogeneous_ && k <= dims_) c[k] = float_of(w);
        else if (k < dims_) finite = finite && finite_in_float(w);
      }
      for (std::size_t k = 0; homogeneous_ && k < dims_; ++k) finite = finite && std::isfinite(c[k] / c[dims_]);
      if (!finite) not_finite_.emplace(v, line_);
    }
  }

  void faces() {
    for (unsigned long long f = 0; f < counts_[1]; ++f) {
      const std::string face = "OFF face " + std::to_string(f + 1) + " of " + std::to_string(counts_[1]);
      if (!next_line())
        throw InputError(name_ + ": OFF data ends before face " + std::to_string(f + 1) + " of " +
                         std::to_string(counts_[1]) + " (truncated file)");
      if (comment_line()) throw InputError(where() + face + kCommentLine);
      std::size_t w_at = 0;
      std::string_view w;
      const bool counted = next_word(l_, w_at, w) && w.find_first_not_of("0123456789") == std::string_view::npos;
      if (!counted) throw InputError(where() + face + ": vertex count " + obj_text::quote(w) + " is not a count");
      if (w.size() > 2 || w == "0" || w == "00" || std::stoi(std::string(w)) > 9)
        throw InputError(where() + face + " has " + std::string(w.substr(0, 15)) +
                         " vertices; the model importer reads faces of 1 to 9");
      const int n = std::stoi(std::string(w));
      for (int k = 0; k < n; ++k) face_index(face, n, k, w_at);
    }
  }
  // Past the faces, blank and comment lines only: the importer stops at
  // the header's count, and dropped a face past it without a word.
  void rest() {
    while (next_line())
      if (l_.find_first_not_of(" \t\v") != std::string_view::npos && !comment_line())
        throw InputError(where() + "OFF data goes on past the " + std::to_string(counts_[1]) +
                         " faces the header counts");
  }
  // Index k of an n-vertex face: digits, within the vertices, finite.
  void face_index(const std::string& face, int n, int k, std::size_t& w_at) {
    std::string_view w;
    if (!next_word(l_, w_at, w))
      throw InputError(where() + face + " needs " + std::to_string(n) + " vertex indices; the line has " +
                       std::to_string(k));
    if (w.find_first_not_of("0123456789") != std::string_view::npos)
      throw InputError(where() + face + ": " + obj_text::quote(w) + " is not a vertex index");
    if (w.size() > 15 || std::stoull(std::string(w)) >= counts_[0])
      throw InputError(where() + face + ": vertex index " + obj_text::quote(w) + " out of range (the file has " +
                       std::to_string(counts_[0]) + " vertices)");
    const auto bad = not_finite_.find(std::stoull(std::string(w)));
    if (bad != not_finite_.end())
      throw InputError(where() + face + ": vertex " + std::string(w) + " (line " + std::to_string(bad->second) +
                       ") is not a finite number");
  }

  const std::string_view t_;
  const std::size_t file_bytes_;
  const std::string& name_;
  std::size_t at_ = 0;
  unsigned long long line_ = 1;
  bool normals_ = false, homogeneous_ = false;
  unsigned long long dims_ = 3;
  unsigned long long counts_[2] = {0, 0};
  std::string_view l_;  // the body's current line
  std::unordered_map<unsigned long long, unsigned long long> not_finite_;
};

}  // namespace

void check_off(const std::string& text, std::size_t file_bytes, const std::string& name) {
  OffCheck(text, file_bytes, name).run();
}

}  // namespace opsila
