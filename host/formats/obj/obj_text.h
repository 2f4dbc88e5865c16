// Strict scanning of OBJ and MTL text, shared by the OBJ reader
// (obj_loader.cpp) and the MTL reader (mtl_parser.cpp): lines, tokens and
// numbers, each problem named by FILE:LINE.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>

#include "formats/common/model_words.h"
#include "scene/scene.h"

namespace opsila {
namespace obj_text {

[[noreturn]] void fail(const std::string& file, int line, const std::string& what);
// "FILE:LINE: ", the start of a message.
std::string at(const std::string& file, int line);
// A token as shown in a message (model_words.h).
using model_words::quote;
bool is_blank(char c);
std::string_view trim(std::string_view s);
// Next blank-separated token of `rest` (empty at the end of the line).
std::string_view next_token(std::string_view& rest);
bool is_identifier(std::string_view s);

// Splits text into lines (\n, \r\n or a lone \r) and refuses binary bytes, so
// every later message can name a line. A line that ends in a backslash
// goes on in the next one (the OBJ and MTL line continuation): the
// statement is their text joined, the backslash and line end read as one
// blank, and it is named by its first line.
class LineScanner {
 public:
  // file_start: the text is the start of the file (where a byte-order mark
  // may stand), not a later chunk of it.
  LineScanner(std::string_view text, const std::string& file, bool file_start = true)
      : p_(text.data()), end_(text.data() + text.size()), file_(file) {
    if (!file_start) return;
    const auto* u = reinterpret_cast<const unsigned char*>(p_);
    const std::size_t n = text.size();
    if (n >= 2 && ((u[0] == 0xfe && u[1] == 0xff) || (u[0] == 0xff && u[1] == 0xfe)))
      fail(file_, 1, "UTF-16 text is not supported (save the file as UTF-8 or ASCII)");
    if (n >= 3 && u[0] == 0xef && u[1] == 0xbb && u[2] == 0xbf) p_ += 3;  // UTF-8 BOM
  }

  bool next(std::string_view& line) {
    if (p_ >= end_) return false;
    first_line_ = lines_ + 1;
    physical(line);
    if (!continued(line)) return true;
    joined_.assign(line.data(), line.size() - 1);
    while (p_ < end_) {
      joined_ += ' ';
      physical(line);
      if (!continued(line)) {
        joined_.append(line.data(), line.size());
        break;
      }
      joined_.append(line.data(), line.size() - 1);
    }
    line = joined_;
    return true;
  }

  // The first line of the statement last read.
  int line_no() const { return first_line_; }
  // Lines read so far (a continued statement counts all of its lines).
  int lines() const { return lines_; }

 private:
  static bool continued(std::string_view line) { return !line.empty() && line.back() == '\\'; }

  void physical(std::string_view& line) {
    const int at_line = ++lines_;
    const char* q = p_;
    for (; q < end_; ++q) {
      const unsigned char c = static_cast<unsigned char>(*q);
      if (c >= 0x20 && c != 0x7f) continue;
      if (c == '\n' || c == '\r') break;
      if (c == '\t') continue;
      if (c == 0) fail(file_, at_line, "NUL byte in text (binary file?)");
      char buf[64];
      std::snprintf(buf, sizeof buf, "control character 0x%02x in text (binary file?)", c);
      fail(file_, at_line, buf);
    }
    line = std::string_view(p_, static_cast<std::size_t>(q - p_));
    if (q < end_) q += (*q == '\r' && q + 1 < end_ && q[1] == '\n') ? 2 : 1;
    p_ = q;
  }

  const char* p_;
  const char* end_;
  const std::string& file_;
  int lines_ = 0, first_line_ = 0;
  std::string joined_;  // a continued statement's lines, joined
};

// Whether the line end at text[i] (a \n, a lone \r, or either byte of a
// \r\n) closes a line that goes on in the next: no split of the text may
// fall there.
inline bool continues_at(std::string_view text, std::size_t i) {
  if (text[i] == '\n' && i > 0 && text[i - 1] == '\r') --i;
  return i > 0 && text[i - 1] == '\\';
}

enum class Num { ok, not_number, not_finite, too_large };

const char* describe(Num s);
Num parse_float(std::string_view tok, float& out);
bool parse_int(std::string_view tok, long long& out);

}  // namespace obj_text
}  // namespace opsila
