// Binary FBX: each zlib-compressed array (vertices, indices, normals, ...)
// must inflate to exactly what its header says, its count times its
// element's size. The importer inflates into a buffer of that size and
// keeps what a short stream left as zeros (vertices moved to the origin,
// indices to vertex 0) without a word. The record layout: a node is its end
// offset, property count and property bytes (32-bit before version 7500,
// 64-bit from it), its name, its properties, then child nodes up to a null
// record; an array property is its type, count, encoding (1: zlib) and byte
// length. A file whose records do not add up is left to the importer,
// which names its own problems.
#include <cstdint>
#include <string>

#include "core/errors.h"
#include "formats/assimp/model_checks.h"

#ifdef OPSILA_HAVE_ZLIB
#include <zlib.h>
#endif

namespace opsila {

#ifdef OPSILA_HAVE_ZLIB

namespace {

using u64 = std::uint64_t;

// What a zlib stream inflates to: its bytes, counting no further than
// `limit` + 1, or why it cannot be inflated (damaged, or cut short).
struct Inflated {
  u64 bytes = 0;
  std::string damage;
};

Inflated inflated_bytes(const unsigned char* data, u64 length, u64 limit) {
  z_stream z{};
  if (inflateInit(&z) != Z_OK) return {0, "the inflater could not start"};
  z.next_in = const_cast<unsigned char*>(data);
  z.avail_in = static_cast<uInt>(length);
  unsigned char out[1 << 16];
  Inflated r;
  int ret = Z_OK;
  while (ret == Z_OK && r.bytes <= limit) {
    z.next_out = out;
    z.avail_out = sizeof out;
    ret = inflate(&z, Z_NO_FLUSH);
    r.bytes += sizeof out - z.avail_out;
  }
  if (ret != Z_STREAM_END && r.bytes <= limit)
    r.damage = ret == Z_BUF_ERROR || (ret == Z_OK && z.avail_in == 0) ? "ends before its zlib stream does"
                                                                        : std::string("is not a valid zlib stream (") +
                                                                              (z.msg ? z.msg : "zlib error") + ")";
  inflateEnd(&z);
  return r;
}

class FbxArrays {
 public:
  FbxArrays(const std::string& bytes, const std::string& name, u64 budget)
      : b_(bytes), name_(name), wide_(number(23, 4) >= 7500), budget_(budget) {}

  void check() {
    u64 at = 27;  // after the magic, two bytes and the version
    while (at < b_.size() && (at = node(at, 0)) != 0) {}
  }

 private:
  u64 number(u64 at, int bytes) const {
    if (at > b_.size() || b_.size() - at < u64(bytes)) return ~u64(0);
    u64 v = 0;
    for (int k = bytes - 1; k >= 0; --k) v = v << 8 | static_cast<unsigned char>(b_[at + u64(k)]);
    return v;
  }

  // The node at `at`: the offset after it, or 0 at a null record or where
  // the records do not add up (the walk stops).
  u64 node(u64 at, int depth) {
    const int w = wide_ ? 8 : 4;
    const u64 end = number(at, w), props = number(at + w, w), head = 3 * u64(w) + 1;
    if (end == 0 || end > b_.size() || end <= at || end - at < head || depth > 64 || props > b_.size()) return 0;
    const u64 name_length = number(at + 3 * w, 1);
    if (name_length > end - at - head) return 0;
    const std::string node_name = b_.substr(at + head, name_length);
    u64 p = at + head + name_length;
    for (u64 k = 0; k < props && p < end; ++k) p = property(p, end, node_name);
    while (p < end && p != 0) {
      const u64 next = node(p, depth + 1);
      if (next == 0) break;  // the null record that closes the children (or a fault)
      p = next;
    }
    return end;
  }

  // The property at `p` (checked if an array): the offset after it, or `end`.
  u64 property(u64 p, u64 end, const std::string& node_name) {
    const char type = b_[p];
    switch (type) {
      case 'C': return p + 2;
      case 'Y': return p + 3;
      case 'I': case 'F': return p + 5;
      case 'D': case 'L': return p + 9;
      case 'S': case 'R': {
        const u64 n = number(p + 1, 4);
        return n > end - p ? end : p + 5 + n;
      }
      case 'b': case 'c': case 'i': case 'f': case 'd': case 'l': {
        const u64 count = number(p + 1, 4), encoding = number(p + 5, 4), length = number(p + 9, 4);
        if (length > end - p || end - p - length < 13) return end;
        if (encoding == 1) compressed(p, count * element_bytes(type), length, node_name);
        return p + 13 + length;
      }
      default: return end;
    }
  }

  static u64 element_bytes(char type) { return type == 'b' || type == 'c' ? 1 : type == 'i' || type == 'f' ? 4 : 8; }

  void compressed(u64 p, u64 expected, u64 length, const std::string& node_name) {
    // Beyond the importer's memory budget its own watch refuses the file;
    // past four budgets inflated the rest is left unchecked (a bound on the time).
    if (expected > budget_ || inflated_ > 4 * budget_) return;
    const Inflated z = inflated_bytes(reinterpret_cast<const unsigned char*>(b_.data()) + p + 13, length, expected);
    const std::string at = name_ + ": FBX array " + node_name + " at byte " + std::to_string(p);
    if (!z.damage.empty()) throw InputError(at + ": its compressed data " + z.damage);
    const u64 got = z.bytes;
    inflated_ += got;
    if (got == expected) return;
    throw InputError(at + ": its compressed data " +
                     (got > expected ? "inflates to more than " : "inflates to " + std::to_string(got) + " of ") +
                     "the " + std::to_string(expected) + " bytes its count gives (damaged or cut short: the model "
                     "importer would read " + (got > expected ? "none of it)" : "zeros for the rest)"));
  }

  const std::string& b_;
  const std::string& name_;
  bool wide_;
  u64 budget_, inflated_ = 0;
};

}  // namespace

void check_fbx_binary(const std::string& bytes, const std::string& name) {
  if (bytes.compare(0, 18, "Kaydara FBX Binary") != 0 || bytes.size() < 27) return;
  FbxArrays(bytes, name, import_memory_budget(bytes.size())).check();
}

#else

void check_fbx_binary(const std::string&, const std::string&) {}  // no inflater in this build, nor an importer

#endif

}  // namespace opsila
