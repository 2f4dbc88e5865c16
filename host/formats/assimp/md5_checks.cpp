// MD5 meshes (.md5mesh, text): the importer's reader trusts every index in
// the file. A weight's joint past the joints, or a vertex's weights past
// the weights, was read and freed out of bounds (a corrupted heap, the
// process killed); an index past its count grows the list to it. So every
// count and index is checked first, naming its line.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/errors.h"
#include "formats/assimp/model_checks.h"
#include "formats/common/model_words.h"

namespace opsila {

namespace {

using model_words::next_word;
using model_words::quote;

class Md5Check {
 public:
  Md5Check(const std::string& text, const std::string& name) : text_(text), name_(name) {}

  void run() {
    while (line_words()) {
      if (words_.empty()) continue;
      const std::string_view key = words_[0];
      if (key == "numJoints") declared_joints_ = count(1, "numJoints");
      else if (key == "joints" && brace()) joints();
      else if (key == "mesh" && brace()) mesh();
    }
    if (declared_joints_ >= 0 && declared_joints_ != joints_)
      fail(joints_line_, "numJoints is " + std::to_string(declared_joints_) + " but the joints block lists " +
                             std::to_string(joints_));
  }

 private:
  // The next line's words, a comment (//) left out; false at the end.
  bool line_words() {
    words_.clear();
    if (at_ >= text_.size()) return false;
    std::size_t end = text_.find('\n', at_);
    if (end == std::string::npos) end = text_.size();
    std::string_view line(text_.data() + at_, end - at_);
    line = line.substr(0, line.find("//"));
    at_ = end + 1;
    ++line_;
    std::size_t k = 0;
    std::string_view w;
    while (next_word(line, k, w)) words_.push_back(w);
    return true;
  }
  bool brace() const { return words_.size() > 1 && words_.back() == "{"; }
  bool closes() const { return !words_.empty() && words_[0] == "}"; }

  [[noreturn]] void fail(long line, const std::string& what) const {
    throw InputError(name_ + ":" + std::to_string(line) + ": MD5 " + what);
  }
  // Word k of the line as a whole number below `below` (-1 allowed with `minus_one`).
  std::int64_t index(std::size_t k, const char* what, std::int64_t below, bool minus_one = false) const {
    if (k >= words_.size()) fail(line_, std::string(what) + " missing");
    const std::string_view w = words_[k];
    if (minus_one && w == "-1") return -1;
    if (w.empty() || w.size() > 10 || w.find_first_not_of("0123456789") != std::string_view::npos)
      fail(line_, std::string(what) + " " + quote(w) + " is not a whole number");
    const std::int64_t n = std::stoll(std::string(w));
    if (n >= below)
      fail(line_, std::string(what) + " " + std::to_string(n) + " out of range (" + std::to_string(below) + ")");
    return n;
  }
  // A count: at most one entry a line of the file.
  std::int64_t count(std::size_t k, const char* what) const {
    return index(k, what, static_cast<std::int64_t>(text_.size()) / 4 + 1);
  }

  void joints() {
    joints_line_ = line_;
    while (line_words() && !closes()) {
      if (words_.empty()) continue;
      // "name" parent ( x y z ) ( x y z ): the parent an earlier joint or -1.
      std::size_t k = 0;
      while (k < words_.size() && (k == 0 || words_[k - 1].back() != '"')) ++k;
      index(k, "joint parent", joints_, true);
      ++joints_;
    }
  }

  void mesh() {
    std::int64_t verts = -1, tris = -1, weights = -1;
    struct Use {
      long line;
      std::int64_t first, count;
    };
    std::vector<Use> vertex_weights;
    std::vector<std::pair<long, std::int64_t>> weight_joints, face_vertices;
    while (line_words() && !closes()) {
      if (words_.empty()) continue;
      const std::string_view key = words_[0];
      if (key == "numverts") verts = count(1, "numverts");
      else if (key == "numtris") tris = count(1, "numtris");
      else if (key == "numweights") weights = count(1, "numweights");
      else if (key == "vert") {
        // vert i ( s t ) first count
        index(1, "vert index", verts < 0 ? 0 : verts);
        vertex_weights.push_back(
            {line_, index(6, "vert's first weight", INT64_MAX), index(7, "vert's weight count", INT64_MAX)});
      } else if (key == "tri") {
        index(1, "tri index", tris < 0 ? 0 : tris);
        for (std::size_t k = 2; k < 5; ++k) face_vertices.push_back({line_, index(k, "tri's vertex", INT64_MAX)});
      } else if (key == "weight") {
        index(1, "weight index", weights < 0 ? 0 : weights);
        weight_joints.push_back({line_, index(2, "weight's joint", INT64_MAX)});
      }
    }
    for (const Use& u : vertex_weights)
      if (u.first + u.count > weights)
        fail(u.line, "vert's weights " + std::to_string(u.first) + " + " + std::to_string(u.count) +
                         " run past the mesh's " + std::to_string(weights < 0 ? 0 : weights) + " weights");
    for (const auto& [line, joint] : weight_joints)
      if (joint >= joints_)
        fail(line, "weight's joint " + std::to_string(joint) + " out of range (" + std::to_string(joints_) + " joints)");
    for (const auto& [line, v] : face_vertices)
      if (v >= verts)
        fail(line, "tri's vertex " + std::to_string(v) + " out of range (" + std::to_string(verts < 0 ? 0 : verts) +
                       " vertices)");
  }

  const std::string& text_;
  const std::string& name_;
  std::size_t at_ = 0;
  long line_ = 0, joints_line_ = 0;
  std::vector<std::string_view> words_;
  std::int64_t declared_joints_ = -1, joints_ = 0;
};

}  // namespace

void check_md5_mesh(const std::string& text, const std::string& name) { Md5Check(text, name).run(); }

}  // namespace opsila
