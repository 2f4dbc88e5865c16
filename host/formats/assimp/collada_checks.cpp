// COLLADA (.dae) words the importer's reader trusts, checked first, naming
// the line (found by hand, Debian's assimp 5.2):
//   - a `count` attribute that is not a whole number: a negative one
//     (`<float_array count="-1">`) faulted inside the reader; an `offset`
//     of -1 was taken as 0, a `stride` of 0 left "no facets";
//   - a primitive's `<p>` indices: a fraction (`1.5`) made the reader grow
//     past 1 GiB, a negative index left "no facets", one past 32 bits
//     wrapped into another index (indices from 2^31 are refused too);
//   - `<skew>`, which the reader fails on, valid as it is.
#include <cctype>
#include <cstdint>
#include <string>
#include <string_view>

#include "core/errors.h"
#include "formats/assimp/model_checks.h"
#include "formats/common/model_words.h"

namespace opsila {

namespace {

using model_words::quote;

// A whole number of at most `most`: a count (32 bits) or an index (31:
// no model the importer can hold has 2^31 vertices).
bool whole_number(std::string_view w, unsigned long long most) {
  return !w.empty() && w.size() <= 10 && w.find_first_not_of("0123456789") == std::string_view::npos &&
         std::stoull(std::string(w)) <= most;
}

class ColladaCheck {
 public:
  ColladaCheck(const std::string& text, const std::string& name) : text_(text), name_(name) {}

  void run() {
    for (std::size_t at = text_.find('<'); at != std::string::npos; at = text_.find('<', at + 1)) {
      if (starts(at, "<!--")) {  // a comment's words are no element's
        at = text_.find("-->", at);
        if (at == std::string::npos) return;
        continue;
      }
      if (starts(at, "<skew") && ends_name(at + 5))
        fail(at, "<skew> (a shear) is a transform the importer cannot read: bake it into the vertices");
      if (starts(at, "<p>")) indices(at + 3);
      else counts(at);
    }
  }

 private:
  bool starts(std::size_t at, std::string_view s) const { return text_.compare(at, s.size(), s) == 0; }
  bool ends_name(std::size_t at) const {
    return at < text_.size() && (text_[at] == '>' || text_[at] == ' ' || text_[at] == '/' || text_[at] == '\t' ||
                                 text_[at] == '\r' || text_[at] == '\n');
  }

  // The line of byte `at`, counted on from the last line found (the scan
  // moves forwards).
  long line_of(std::size_t at) {
    for (; counted_ < at && counted_ < text_.size(); ++counted_) line_ += text_[counted_] == '\n';
    return line_;
  }
  [[noreturn]] void fail(std::size_t at, const std::string& what) {
    throw InputError(name_ + ":" + std::to_string(line_of(at)) + ": COLLADA " + what);
  }

  // The count, offset, stride and set attributes of the tag at `at`, each
  // a whole number (a stride at least 1: 0 left "no facets").
  void counts(std::size_t at) {
    const std::size_t end = text_.find('>', at);
    if (end == std::string::npos) return;
    const std::string_view tag = std::string_view(text_).substr(at, end - at);
    for (const std::string_view key : {"count=", "offset=", "stride=", "set="})
      for (std::size_t k = tag.find(key); k != std::string_view::npos; k = tag.find(key, k + key.size())) {
        const std::size_t open = k + key.size();
        if (!std::isspace(static_cast<unsigned char>(tag[k - 1])) || open >= tag.size()) continue;
        const std::size_t close = tag[open] == '"' || tag[open] == '\'' ? tag.find(tag[open], open + 1)
                                                                         : std::string_view::npos;
        if (close == std::string_view::npos) continue;
        const std::string_view v = tag.substr(open + 1, close - open - 1);
        if (!whole_number(v, 0xFFFFFFFFull) || (key == "stride=" && std::stoull(std::string(v)) == 0))
          fail(at + k, std::string(key) + quote(v) + " is not a whole number" +
                           (key == "stride=" ? " of at least 1" : " of at most 32 bits"));
      }
  }

  // The words of a <p> from `at` to its </p>: whole numbers below 2^32.
  void indices(std::size_t at) {
    const std::size_t end = text_.find("</p>", at);
    if (end == std::string::npos) return;
    const std::string_view body = std::string_view(text_).substr(at, end - at);
    std::size_t k = 0;
    std::string_view w;
    while (model_words::next_word(body, k, w))
      if (!whole_number(w, 0x7FFFFFFFull))
        fail(at + k - w.size(), "<p> index " + quote(w) + " is not an index (a whole number below 2^31)");
  }

  const std::string& text_;
  const std::string& name_;
  std::size_t counted_ = 0;
  long line_ = 1;
};

}  // namespace

void check_collada(const std::string& text, const std::string& name) { ColladaCheck(text, name).run(); }

}  // namespace opsila
