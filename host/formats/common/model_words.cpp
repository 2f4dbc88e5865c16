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

bool number_start(std::string_view w) {
  std::size_t i = w.size() > 0 && (w[0] == '-' || w[0] == '+') ? 1 : 0;
  const auto digit = [&](std::size_t k) { return k < w.size() && w[k] >= '0' && w[k] <= '9'; };
  if (digit(i) || (i < w.size() && w[i] == '.' && digit(i + 1))) return true;
  const std::string rest = lower(std::string(w.substr(i, 3)));
  return rest == "nan" || rest == "inf";
}

std::string quote(std::string_view tok) {
  std::string out = "'";
  const std::size_t limit = 40;
  for (std::size_t i = 0; i < tok.size() && i < limit; ++i) {
    const unsigned char c = static_cast<unsigned char>(tok[i]);
    if (c < 0x20 || c >= 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    } else {
      out += static_cast<char>(c);
    }
  }
  if (tok.size() > limit) out += "...";
  return out + "'";
}

}  // namespace opsila::model_words
