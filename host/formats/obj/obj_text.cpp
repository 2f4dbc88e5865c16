// Strict scanning of OBJ and MTL text (see obj_text.h), and the text check
// of input files.
#include "formats/obj/obj_text.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <system_error>
#include <vector>

#include "core/stage_clock.h"
#include "formats/obj/obj_loader.h"

namespace opsila {

namespace fs = std::filesystem;

namespace obj_text {

[[noreturn]] void fail(const std::string& file, int line, const std::string& what) {
  throw InputError(file + ":" + std::to_string(line) + ": " + what);
}

std::string at(const std::string& file, int line) {
  return file + ":" + std::to_string(line) + ": ";
}

bool is_blank(char c) { return c == ' ' || c == '\t'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_blank(s.back())) s.remove_suffix(1);
  return s;
}

// Next blank-separated token of `rest` (empty at the end of the line).
std::string_view next_token(std::string_view& rest) {
  std::size_t i = 0;
  while (i < rest.size() && is_blank(rest[i])) ++i;
  std::size_t j = i;
  while (j < rest.size() && !is_blank(rest[j])) ++j;
  std::string_view tok = rest.substr(i, j - i);
  rest.remove_prefix(j);
  return tok;
}

bool is_identifier(std::string_view s) {
  if (s.empty()) return false;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const char c = s[i];
    const bool alpha = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_';
    const bool digit = c >= '0' && c <= '9';
    if (!(alpha || (digit && i > 0))) return false;
  }
  return true;
}

const char* describe(Num s) {
  switch (s) {
    case Num::not_number: return "is not a number";
    case Num::not_finite: return "is not finite";
    case Num::too_large: return "is too large for float";
    default: return "is fine";
  }
}

Num parse_float(std::string_view tok, float& out) {
  const char* s = tok.data();
  const char* e = s + tok.size();
  // from_chars refuses a leading '+', which OBJ writers do emit.
  if (s < e && *s == '+') {
    ++s;
    if (s < e && (*s == '+' || *s == '-')) return Num::not_number;
  }
  if (s == e) return Num::not_number;
  auto r = std::from_chars(s, e, out);
  if (r.ec == std::errc::result_out_of_range) {
    double d = 0;
    auto rd = std::from_chars(s, e, d);
    if (rd.ptr != e) return Num::not_number;
    if (rd.ec == std::errc() && std::fabs(d) < 1.0) {  // underflow: a tiny number
      out = static_cast<float>(d);
      return Num::ok;
    }
    if (rd.ec == std::errc::result_out_of_range) {
      // Either way past double; decide by the exponent's sign.
      const char* x = s;
      while (x < e && *x != 'e' && *x != 'E') ++x;
      if (x + 1 < e && x[1] == '-') {
        out = 0.0f;
        return Num::ok;
      }
    }
    return Num::too_large;
  }
  if (r.ec != std::errc() || r.ptr != e) return Num::not_number;
  if (!std::isfinite(out)) return Num::not_finite;
  return Num::ok;
}

bool parse_int(std::string_view tok, long long& out) {
  const char* s = tok.data();
  const char* e = s + tok.size();
  if (s < e && *s == '+') ++s;
  if (s == e || *s == '+') return false;
  auto r = std::from_chars(s, e, out);
  return r.ec == std::errc() && r.ptr == e;
}

}  // namespace obj_text

}  // namespace opsila
