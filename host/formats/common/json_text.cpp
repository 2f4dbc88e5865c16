#include "formats/common/json_text.h"

#include <cctype>
#include <cstdio>
#include <string_view>
#include <unordered_set>
#include <vector>

#include "scene/scene.h"

namespace opsila {

namespace {

bool is_control(unsigned char c) { return c < 0x20 || c == 0x7f; }

}  // namespace

std::string quoted_prefix(const std::string& text) {
  std::size_t cut = text.size();
  if (cut > kMaxQuoted) {
    cut = kMaxQuoted;
    // Back up to the start of a UTF-8 character.
    while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;
  }
  std::string out = text.substr(0, cut);
  for (char& c : out)
    if (is_control(static_cast<unsigned char>(c))) c = '?';
  if (cut < text.size()) out += "...";
  return out;
}

std::string shown_path(const std::string& path) {
  if (path.size() <= kMaxQuoted) return quoted_prefix(path);
  std::string out, segment;
  for (char c : path) {
    if (c == '.' || c == '[') {
      out += quoted_prefix(segment);
      segment.clear();
      out += c;
    } else {
      segment += c;
    }
  }
  return out + quoted_prefix(segment);
}

std::string lone_cr_as_lf(std::string text) {
  for (std::size_t k = 0; k < text.size(); ++k)
    if (text[k] == '\r' && (k + 1 == text.size() || text[k + 1] != '\n')) text[k] = '\n';
  return text;
}

void check_json_bytes(const char* data, std::size_t size, std::size_t offset, int& line,
                      const std::string& name) {
  for (std::size_t k = 0; k < size; ++k) {
    const unsigned char c = static_cast<unsigned char>(data[k]);
    if (c == '\n' || (c == '\r' && k + 1 < size && data[k + 1] != '\n')) ++line;
    if (!is_control(c) || c == '\n' || c == '\r' || c == '\t') continue;
    char code[8];
    std::snprintf(code, sizeof code, "0x%02x", c);
    throw InputError(name + ":" + std::to_string(line) + ": byte " + code + " at offset " +
                     std::to_string(offset + k) +
                     (c == 0 ? " (a NUL: not a JSON text file)"
                             : " (a control character: not allowed in JSON text)"));
  }
}

void check_json_shape(const std::string& text, const std::string& name, int max_depth,
                      int max_keys) {
  std::vector<int> keys(1, 0);  // members seen in each open object or array
  int line = 1;
  bool in_string = false, escaped = false;
  for (char c : text) {
    if (c == '\n') ++line;
    if (in_string) {
      if (escaped) escaped = false;
      else if (c == '\\') escaped = true;
      else if (c == '"') in_string = false;
      continue;
    }
    if (c == '"') {
      in_string = true;
    } else if (c == '{' || c == '[') {
      if (static_cast<int>(keys.size()) > max_depth)
        throw InputError(name + ":" + std::to_string(line) + ": nesting deeper than " +
                         std::to_string(max_depth) + " levels");
      keys.push_back(0);
    } else if (c == '}' || c == ']') {
      if (keys.size() > 1) keys.pop_back();
    } else if (c == ':' && ++keys.back() > max_keys) {
      throw InputError(name + ":" + std::to_string(line) + ": more than " +
                       std::to_string(max_keys) + " keys in one object");
    }
  }
}

void check_json_nul_escapes(const std::string& text, const std::string& name) {
  int line = 1;
  bool in_string = false;
  for (std::size_t k = 0; k < text.size(); ++k) {
    const char c = text[k];
    if (c == '\n') ++line;
    if (!in_string) {
      in_string = c == '"';
    } else if (c == '"') {
      in_string = false;
    } else if (c == '\\') {
      if (text.compare(k + 1, 5, "u0000") == 0)
        throw InputError(name + ":" + std::to_string(line) + ": a string may not hold \\u0000 (a NUL)");
      ++k;  // the escaped character, a quote or a backslash among them
    }
  }
}

// ----------------------------------------------------------- JsonLines ---

JsonLines::JsonLines(const std::string& text, const std::string& name,
                     std::vector<std::string>& warnings)
    : s_(text), name_(name), warnings_(warnings) {
  if (s_.compare(0, 3, "\xEF\xBB\xBF") == 0) i_ = 3;  // UTF-8 BOM, as nlohmann skips it
  value();
}

void JsonLines::ws() {
  while (i_ < s_.size()) {
    const char c = s_[i_];
    if (c == '\n') ++line_;
    else if (c != ' ' && c != '\t' && c != '\r') break;
    ++i_;
  }
}

namespace {

// The four hex digits of a \u escape at s[at], or -1.
long hex4(const std::string& s, std::size_t at) {
  if (at + 4 > s.size()) return -1;
  long v = 0;
  for (std::size_t k = at; k < at + 4; ++k) {
    const int d = std::isdigit(static_cast<unsigned char>(s[k])) ? s[k] - '0'
                  : std::isxdigit(static_cast<unsigned char>(s[k])) ? (std::tolower(s[k]) - 'a' + 10) : -1;
    if (d < 0) return -1;
    v = v * 16 + d;
  }
  return v;
}

void append_utf8(std::string& out, long c) {
  if (c < 0x80) {
    out += char(c);
  } else if (c < 0x800) {
    out += {char(0xC0 | (c >> 6)), char(0x80 | (c & 0x3F))};
  } else if (c < 0x10000) {
    out += {char(0xE0 | (c >> 12)), char(0x80 | ((c >> 6) & 0x3F)), char(0x80 | (c & 0x3F))};
  } else {
    out += {char(0xF0 | (c >> 18)), char(0x80 | ((c >> 12) & 0x3F)), char(0x80 | ((c >> 6) & 0x3F)),
            char(0x80 | (c & 0x3F))};
  }
}

}  // namespace

// Decoded as the JSON library decodes it (keys must compare alike: a key
// spelt with \u escapes is the same key, given twice or looked up).
std::string JsonLines::string() {
  std::string out;
  ++i_;  // opening quote
  while (i_ < s_.size() && s_[i_] != '"') {
    if (s_[i_] != '\\' || i_ + 1 >= s_.size()) {
      out += s_[i_++];
      continue;
    }
    const char e = s_[i_ + 1];
    i_ += 2;
    if (e != 'u') {
      out += e == 'n' ? '\n' : e == 't' ? '\t' : e == 'r' ? '\r' : e == 'b' ? '\b' : e == 'f' ? '\f' : e;
      continue;
    }
    long c = hex4(s_, i_);
    i_ += c < 0 ? 0 : 4;
    const long low = c >= 0xD800 && c < 0xDC00 && s_.compare(i_, 2, "\\u") == 0 ? hex4(s_, i_ + 2) : -1;
    if (low >= 0xDC00 && low < 0xE000) {
      c = 0x10000 + ((c - 0xD800) << 10) + (low - 0xDC00);
      i_ += 6;
    }
    append_utf8(out, c < 0 ? '?' : c);
  }
  ++i_;  // closing quote
  return out;
}

std::string JsonLines::current_path() const {
  std::string path;
  for (const std::string& segment : stack_)
    path += (path.empty() || segment[0] == '[') ? segment : "." + segment;
  return path;
}

// Reads one value; returns its node. Only paths of duplicate keys are ever
// spelled out, so deep paths over long arrays cost nothing.
int JsonLines::value() {
  ws();
  const int node = static_cast<int>(nodes_.size());
  nodes_.push_back(Node{line_, -1, -1, false});
  const char c = i_ < s_.size() ? s_[i_] : '\0';
  if (c == '{' || c == '[') {
    const bool is_object = c == '{';
    nodes_[node].is_object = is_object;
    ++i_;
    ws();
    if (i_ < s_.size() && s_[i_] == (is_object ? '}' : ']')) {
      ++i_;
      return node;
    }
    int last = -1;
    for (std::size_t k = 0;; ++k) {
      ws();
      int child;
      if (is_object) {
        const int key_line = line_;
        std::string key = string();
        ws();
        ++i_;  // ':'
        stack_.push_back(key);
        child = value();
        nodes_[child].line = key_line;  // a member's line is its key's
        auto [it, fresh] = members_.emplace(std::to_string(node) + ":" + key, child);
        if (!fresh) {
          warnings_.push_back(name_ + ":" + std::to_string(key_line) + ": " +
                              shown_path(current_path()) + ": key given twice; the last one is used");
          it->second = child;
        }
      } else {
        stack_.push_back("[" + std::to_string(k) + "]");
        child = value();
      }
      stack_.pop_back();
      if (last < 0) nodes_[node].first_child = child;
      else nodes_[last].next_sibling = child;
      last = child;
      ws();
      const bool more = i_ < s_.size() && s_[i_] == ',';
      ++i_;  // ',' or the closing bracket
      if (!more) return node;
    }
  }
  if (c == '"') {
    string();
    return node;
  }
  while (i_ < s_.size() && std::string_view(",]} \t\r\n").find(s_[i_]) == std::string_view::npos)
    ++i_;
  return node;
}

// Follows the path from the root. A key may itself contain '.' or '[', so
// cut points are tried, shortest key first (a few only: a hostile key full of
// dots then costs a few lookups, and the line of its parent is used).
int JsonLines::line_of(const std::string& path) const {
  if (nodes_.empty()) return 1;
  int node = 0;
  std::size_t pos = 0;
  while (pos < path.size()) {
    const Node& n = nodes_[node];
    if (n.first_child < 0) break;
    if (!n.is_object) {
      if (path[pos] != '[') break;
      const std::size_t close = path.find(']', pos);
      if (close == std::string::npos) break;
      std::size_t index = 0;
      for (std::size_t k = pos + 1; k < close; ++k) index = index * 10 + std::size_t(path[k] - '0');
      int child = n.first_child;
      for (std::size_t k = 0; k < index && child >= 0; ++k) child = nodes_[child].next_sibling;
      if (child < 0) break;
      node = child;
      pos = close + 1;
      continue;
    }
    if (pos > 0) {
      if (path[pos] != '.') break;
      ++pos;
    }
    const std::string prefix = std::to_string(node) + ":";
    int next = -1, tries = 0;
    std::size_t end = pos;
    for (; next < 0 && end <= path.size() && tries < 8; ++end) {
      if (end < path.size() && path[end] != '.' && path[end] != '[') continue;
      ++tries;
      auto it = members_.find(prefix + path.substr(pos, end - pos));
      if (it != members_.end()) next = it->second;
    }
    if (next < 0) break;
    node = next;
    pos = end - 1;
  }
  return nodes_[node].line;
}

}  // namespace opsila
