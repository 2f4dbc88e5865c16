#include "formats/common/model_words.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "core/util.h"

namespace opsila::model_words {

bool next_word(std::string_view text, std::size_t& at, std::string_view& out) {
  while (at < text.size() && std::isspace(static_cast<unsigned char>(text[at]))) ++at;
  const std::size_t start = at;
  while (at < text.size() && !std::isspace(static_cast<unsigned char>(text[at]))) ++at;
  out = text.substr(start, at - start);
  return at > start;
}

float float_of(std::string_view w) { return static_cast<float>(std::strtod(std::string(w).c_str(), nullptr)); }

// Every vertex value of a text file passes here, so plain decimals short
// enough to stay below the float range (no letter, so no exponent, nan or
// inf; at most 38 characters) skip strtod.
bool finite_in_float(std::string_view w) {
  if (w.size() <= 38 && w.find_first_not_of("0123456789+-.") == std::string_view::npos) return true;
  return std::isfinite(float_of(w));
}

bool whole_number(std::string_view w) {
  const std::size_t n = w.size();
  std::size_t i = n > 0 && (w[0] == '-' || w[0] == '+') ? 1 : 0;
  const std::string rest = lower(std::string(w.substr(i, 9)));
  if (rest == "nan" || rest == "inf" || rest == "infinity") return i + rest.size() == n;
  const auto digits = [&] {
    const std::size_t from = i;
    while (i < n && w[i] >= '0' && w[i] <= '9') ++i;
    return i - from;
  };
  std::size_t mantissa = digits();
  if (i < n && w[i] == '.') ++i, mantissa += digits();
  if (mantissa == 0) return false;
  if (i < n && (w[i] == 'e' || w[i] == 'E')) {
    ++i;
    if (i < n && (w[i] == '-' || w[i] == '+')) ++i;
    if (digits() == 0) return false;
  }
  return i == n;
}

namespace {

// One byte as a message shows it: printable ASCII as it is, others \xNN.
void show_byte(std::string& out, unsigned char c) {
  if (c >= 0x20 && c < 0x7f) {
    out += static_cast<char>(c);
    return;
  }
  char buf[8];
  std::snprintf(buf, sizeof buf, "\\x%02x", c);
  out += buf;
}

}  // namespace

std::string quote(std::string_view tok) {
  std::string out = "'";
  const std::size_t limit = 40;
  for (std::size_t i = 0; i < tok.size() && i < limit; ++i) show_byte(out, static_cast<unsigned char>(tok[i]));
  if (tok.size() > limit) out += "...";
  return out + "'";
}

std::string one_line(std::string_view text, std::size_t most) {
  std::string out;
  std::size_t i = 0;
  for (; i < text.size() && out.size() < most; ++i) {
    const char c = text[i];
    if (c == '\n' || c == '\r' || c == '\t') out += ' ';
    else show_byte(out, static_cast<unsigned char>(c));
  }
  if (i < text.size()) out += "...";
  return out;
}

}  // namespace opsila::model_words
