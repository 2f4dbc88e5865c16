// Strict scanning of OBJ and MTL text, shared by the OBJ reader
// (obj_loader.cpp) and the MTL reader (mtl_parser.cpp): lines, tokens and
// numbers, each problem named by FILE:LINE.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>

#include "core/scene.h"

namespace opsila {
namespace obj_text {

[[noreturn]] void fail(const std::string& file, int line, const std::string& what);
// "FILE:LINE: ", the start of a message.
std::string at(const std::string& file, int line);
// A token as shown in a message: quoted, shortened, control bytes escaped.
std::string quote(std::string_view tok);
bool is_blank(char c);
std::string_view trim(std::string_view s);
// Next blank-separated token of `rest` (empty at the end of the line).
std::string_view next_token(std::string_view& rest);
bool is_identifier(std::string_view s);

// Splits text into lines (\n, \r\n or a lone \r) and refuses binary bytes, so
// every later message can name a line.
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
    ++line_no_;
    const char* q = p_;
    for (; q < end_; ++q) {
      const unsigned char c = static_cast<unsigned char>(*q);
      if (c >= 0x20 && c != 0x7f) continue;
      if (c == '\n' || c == '\r') break;
      if (c == '\t') continue;
      if (c == 0) fail(file_, line_no_, "NUL byte in text (binary file?)");
      char buf[64];
      std::snprintf(buf, sizeof buf, "control character 0x%02x in text (binary file?)", c);
      fail(file_, line_no_, buf);
    }
    line = std::string_view(p_, static_cast<std::size_t>(q - p_));
    if (q < end_) q += (*q == '\r' && q + 1 < end_ && q[1] == '\n') ? 2 : 1;
    p_ = q;
    return true;
  }

  int line_no() const { return line_no_; }

 private:
  const char* p_;
  const char* end_;
  const std::string& file_;
  int line_no_ = 0;
};

enum class Num { ok, not_number, not_finite, too_large };

const char* describe(Num s);
Num parse_float(std::string_view tok, float& out);
bool parse_int(std::string_view tok, long long& out);

}  // namespace obj_text
}  // namespace opsila
