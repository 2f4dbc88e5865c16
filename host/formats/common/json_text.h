// The text of a JSON scene file before and around nlohmann::json: bytes
// that cannot be JSON, nesting, the line of every key path (for messages),
// and short quotes of keys and values. Everything here is linear in the size
// of the text, so a hostile file costs at most a small multiple of its size.
#pragma once

#include <cstddef>
#include <string>
#include <unordered_map>
#include <vector>

namespace opsila {

// At most this many bytes of a key or value are quoted in a message.
constexpr std::size_t kMaxQuoted = 40;

// `text` cut to kMaxQuoted bytes (on a UTF-8 character boundary, "..."
// appended when cut), control characters shown as '?', so a message stays
// one short line whatever the input holds.
std::string quoted_prefix(const std::string& text);

// A key path (objects[3].material.Kd) with every over-long key shortened by
// quoted_prefix.
std::string shown_path(const std::string& path);

// The text with each carriage return that no line feed follows (a file
// with the classic Mac OS line ends) made a line feed, byte for byte in
// place: JSON reads both as blank space (a raw one in a string is an error
// either way), and the line of every message counts line feeds.
std::string lone_cr_as_lf(std::string text);

// Throws InputError("NAME:LINE: ...") at the first byte that no JSON text may
// hold (a NUL or another control character outside strings and whitespace
// alike), so that text after a NUL is never silently ignored.
void check_json_bytes(const char* data, std::size_t size, std::size_t offset, int& line,
                      const std::string& name);

// Throws InputError("NAME:LINE: ...") past `max_depth` levels of nesting or
// `max_keys` keys in one object (the JSON library finds keys by a linear
// search, so many keys in one object would cost quadratic time).
void check_json_shape(const std::string& text, const std::string& name, int max_depth,
                      int max_keys);

// Throws InputError("NAME:LINE: ...") at the first string or key whose
// text holds the escape \u0000: a reader that keeps names as C strings cuts
// one there, and would open another file than the one written (a glTF's
// "uri": "a.bin\u0000x" read a.bin).
void check_json_nul_escapes(const std::string& text, const std::string& name);

// Line of every key path in syntactically valid JSON text (keys as written;
// a key with escapes may miss, and then its parent's line is used). Memory is
// a few bytes per value and each key is stored once, whatever the depth.
class JsonLines {
 public:
  // Duplicate keys are appended to `warnings` ("key given twice").
  JsonLines(const std::string& text, const std::string& name, std::vector<std::string>& warnings);
  int line_of(const std::string& path) const;

 private:
  // One per value, in text order; children are chained, so a value costs
  // the same few bytes whatever it holds.
  struct Node {
    int line = 1;
    int first_child = -1, next_sibling = -1;
    bool is_object = false;
  };
  int value();
  void ws();
  std::string string();
  std::string current_path() const;

  const std::string& s_;
  const std::string& name_;
  std::vector<std::string>& warnings_;
  std::size_t i_ = 0;
  int line_ = 1;
  std::vector<Node> nodes_;
  std::unordered_map<std::string, int> members_;  // "OBJECT_NODE:key" -> member's node
  std::vector<std::string> stack_;  // key path of the value being read, one segment each
};

}  // namespace opsila
