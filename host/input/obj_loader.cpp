// Strict OBJ/MTL scanning. Geometry and materials are parsed here rather than
// with tinyobjloader: it turns non-numbers into 0, reads "Ks 0.5" as
// (0.5, 0, 0) and reports no line numbers, and the project promises one
// precise FILE:LINE message for every bad input.
#include "input/obj_loader.h"

#include <cerrno>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <new>
#include <stdexcept>
#include <string_view>
#include <system_error>
#include <unordered_map>
#include <unordered_set>

namespace opsila {

namespace fs = std::filesystem;

namespace {

// ---------------------------------------------------------------- text ----

[[noreturn]] void fail(const std::string& file, int line, const std::string& what) {
  throw InputError(file + ":" + std::to_string(line) + ": " + what);
}

std::string at(const std::string& file, int line) {
  return file + ":" + std::to_string(line) + ": ";
}

// A token as shown in a message: quoted, shortened, control bytes escaped.
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

// Splits text into lines (\n, \r\n or a lone \r) and refuses binary bytes, so
// every later message can name a line.
class LineScanner {
 public:
  LineScanner(std::string_view text, const std::string& file)
      : p_(text.data()), end_(text.data() + text.size()), file_(file) {
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

// Statements of the OBJ specification that do not change the image.
bool is_ignored_obj_statement(std::string_view kw) {
  static const char* const names[] = {
      "vt", "vn", "vp", "l", "p", "s", "mg", "cstype", "deg", "bmat", "step", "curv",
      "curv2", "surf", "parm", "trim", "hole", "scrv", "sp", "end", "con", "bevel",
      "c_interp", "d_interp", "lod", "maplib", "usemap", "shadow_obj", "trace_obj",
      "ctech", "stech", "call", "csh"};
  for (const char* n : names)
    if (kw == n) return true;
  return false;
}

// ---------------------------------------------------------------- MTL -----

// Reads "K r [g b]" (g = b = r when only r is given, as MTL says).
void parse_colour(std::string_view rest, std::string_view key, const std::string& file,
                  int line, Vec3& out) {
  float v[3];
  int n = 0;
  for (std::string_view tok = next_token(rest); !tok.empty(); tok = next_token(rest)) {
    if (tok[0] == '#') break;
    if (n == 3)
      fail(file, line, "'" + std::string(key) + "' has more than 3 values");
    float x;
    const Num s = parse_float(tok, x);
    if (s != Num::ok)
      fail(file, line, "'" + std::string(key) + "' value " + quote(tok) + " " + describe(s));
    v[n++] = x;
  }
  if (n == 1) {
    out = {v[0], v[0], v[0]};
  } else if (n == 3) {
    out = {v[0], v[1], v[2]};
  } else {
    fail(file, line, "truncated '" + std::string(key) + "' line: expected 1 or 3 numbers, found " +
                         std::to_string(n));
  }
}

float parse_single(std::string_view rest, std::string_view key, const std::string& file,
                   int line) {
  std::string_view tok = next_token(rest);
  if (tok.empty() || tok[0] == '#')
    fail(file, line, "truncated '" + std::string(key) + "' line: expected a number");
  float x;
  const Num s = parse_float(tok, x);
  if (s != Num::ok)
    fail(file, line, "'" + std::string(key) + "' value " + quote(tok) + " " + describe(s));
  std::string_view extra = next_token(rest);
  if (!extra.empty() && extra[0] != '#')
    fail(file, line, "'" + std::string(key) + "' has more than one value");
  return x;
}

}  // namespace

std::vector<MaterialDesc> parse_mtl(const std::string& text, const std::string& name,
                                    std::vector<std::string>& warnings) {
  std::vector<MaterialDesc> out;
  LineScanner sc(text, name);
  std::string_view line;
  int orphan_keys = 0, orphan_line = 0;
  while (sc.next(line)) {
    const int ln = sc.line_no();
    std::string_view rest = line;
    const std::string_view kw = next_token(rest);
    if (kw.empty() || kw[0] == '#') continue;
    if (kw == "newmtl") {
      MaterialDesc m;  // SPEC defaults for keys left out
      m.name = std::string(trim(rest));
      out.push_back(std::move(m));
      continue;
    }
    const bool known = kw == "Ka" || kw == "Kd" || kw == "Ks" || kw == "Tf" || kw == "Ns" ||
                       kw == "Ni" || kw == "illum";
    if (!known) {
      if (!is_identifier(kw)) fail(name, ln, "invalid statement " + quote(kw) + " (binary file?)");
      continue;  // d, Tr, Ke, map_Kd, bump, ...: no effect on the image
    }
    if (out.empty()) {
      if (orphan_keys++ == 0) orphan_line = ln;
      continue;
    }
    MaterialDesc& m = out.back();
    if (kw == "Ka" || kw == "Kd" || kw == "Ks" || kw == "Tf") {
      std::string_view probe = rest;
      const std::string_view first = next_token(probe);
      if (first == "spectral" || first == "xyz") {
        warnings.push_back(at(name, ln) + "'" + std::string(kw) + " " + std::string(first) +
                           "' is not supported (only RGB); material '" + m.name + "' keeps " +
                           std::string(kw) + " = 0");
        continue;
      }
      Vec3& c = kw == "Ka" ? m.ka : kw == "Kd" ? m.kd : kw == "Ks" ? m.ks : m.tf;
      parse_colour(rest, kw, name, ln, c);
    } else if (kw == "Ns") {
      m.ns = parse_single(rest, kw, name, ln);
    } else if (kw == "Ni") {
      m.ni = parse_single(rest, kw, name, ln);
    } else {  // illum
      std::string_view tok = next_token(rest);
      long long v = 0;
      if (tok.empty() || tok[0] == '#') fail(name, ln, "truncated 'illum' line: expected 0..10");
      if (!parse_int(tok, v) || v < 0 || v > 10)
        fail(name, ln, "'illum' value " + quote(tok) + " is not an integer in 0..10");
      std::string_view extra = next_token(rest);
      if (!extra.empty() && extra[0] != '#') fail(name, ln, "'illum' has more than one value");
      m.illum = static_cast<int>(v);
    }
  }
  if (orphan_keys > 0)
    warnings.push_back(at(name, orphan_line) + std::to_string(orphan_keys) +
                       " material keys before the first 'newmtl' were ignored");
  for (const MaterialDesc& m : out) {
    if (illum_transmits(m.illum) && !(m.ni > 0))
      warnings.push_back(name + ": material '" + m.name +
                         "' transmits light but has Ni <= 0 (refraction is undefined)");
  }
  return out;
}

std::string read_input_file(const std::string& path) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st)) {
    const std::string why = ec ? ec.message() : "no such file";
    throw InputError(path + ": cannot open: " + why);
  }
  if (fs::is_directory(st)) throw InputError(path + ": is a directory, not a file");
  if (!fs::is_regular_file(st)) throw InputError(path + ": is not a regular file");
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) throw InputError(path + ": cannot read: " + ec.message());
  if (size > kMaxInputFileBytes)
    throw InputError(path + ": file too large (" + std::to_string(size) +
                     " bytes; the limit is " + std::to_string(kMaxInputFileBytes) + ")");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open: " + std::strerror(errno));
  std::string text;
  try {
    text.resize(static_cast<std::size_t>(size));
  } catch (const std::bad_alloc&) {
    throw InputError(path + ": out of memory reading the file");
  }
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (static_cast<std::uintmax_t>(in.gcount()) != size)
    throw InputError(path + ": read error (file changed or unreadable)");
  return text;
}

// ---------------------------------------------------------------- OBJ -----

namespace {

struct Polygon {
  std::uint32_t first;  // into the flat index list
  std::uint32_t count;
  int line;
  int section_o, section_g;  // 0-based index of the o / g section (clamped)
  int slot;                  // usemtl slot, -1 = no material
};

class ObjParser {
 public:
  ObjParser(std::string_view text, const std::string& name, const std::string& base_dir)
      : text_(text), name_(name), base_dir_(base_dir) {}

  Scene run() {
    if (text_.size() > kMaxInputFileBytes)
      throw InputError(name_ + ": input too large (" + std::to_string(text_.size()) + " bytes)");
    LineScanner sc(text_, name_);
    std::string_view line;
    while (sc.next(line)) {
      line_ = sc.line_no();
      std::string_view rest = line;
      const std::string_view kw = next_token(rest);
      if (kw.empty() || kw[0] == '#') continue;
      if (kw == "v") {
        vertex(rest);
      } else if (kw == "f") {
        face(rest);
      } else if (kw == "vt" || kw == "vn") {
        continue;
      } else if (kw == "o") {
        ++o_count_;
      } else if (kw == "g") {
        ++g_count_;
      } else if (kw == "usemtl") {
        usemtl(rest);
      } else if (kw == "mtllib") {
        mtllib(rest);
      } else if (is_ignored_obj_statement(kw)) {
        continue;
      } else if (is_identifier(kw)) {
        if (unknown_count_++ == 0) {
          unknown_line_ = line_;
          unknown_first_ = std::string(kw);
        }
      } else {
        fail(name_, line_, "invalid statement " + quote(kw) + " (binary file or not OBJ?)");
      }
    }
    return finish();
  }

 private:
  void vertex(std::string_view rest) {
    float xyz[3] = {0, 0, 0};
    int n = 0;
    for (std::string_view tok = next_token(rest); !tok.empty(); tok = next_token(rest)) {
      if (tok[0] == '#') break;
      float x;
      const Num s = parse_float(tok, x);
      if (s != Num::ok)
        fail(name_, line_, "'v' value " + std::to_string(n + 1) + " " + quote(tok) + " " +
                               describe(s));
      if (n < 3) xyz[n] = x;
      ++n;
    }
    if (n < 3)
      fail(name_, line_, "truncated 'v' line: " + std::to_string(n) + " of 3 coordinates");
    // x y z, optionally w, or the common vertex-colour extension r g b [a].
    if (n > 7)
      fail(name_, line_, "'v' line has " + std::to_string(n) + " values (at most 7 expected)");
    verts_.insert(verts_.end(), xyz, xyz + 3);
  }

  // One "v", "v/vt", "v//vn" or "v/vt/vn" reference; returns the 0-based
  // vertex index (a positive one is range-checked at the end of the file,
  // since it may name a vertex defined further down).
  std::uint32_t vertex_ref(std::string_view tok) {
    const std::size_t s1 = tok.find('/');
    const std::string_view vpart = tok.substr(0, s1);
    bool ok = true;
    if (s1 != std::string_view::npos) {
      std::string_view tail = tok.substr(s1 + 1);
      const std::size_t s2 = tail.find('/');
      const std::string_view tpart = tail.substr(0, s2);
      long long dummy = 0;
      if (s2 == std::string_view::npos) {
        ok = parse_int(tpart, dummy) && dummy != 0;  // v/vt
      } else {
        const std::string_view npart = tail.substr(s2 + 1);
        ok = (tpart.empty() || (parse_int(tpart, dummy) && dummy != 0)) &&
             parse_int(npart, dummy) && dummy != 0;  // v//vn or v/vt/vn
      }
    }
    long long vi = 0;
    if (!ok || !parse_int(vpart, vi))
      fail(name_, line_, "bad vertex reference " + quote(tok) +
                             " in 'f' line (expected v, v/vt, v//vn or v/vt/vn with non-zero "
                             "integers)");
    if (vi == 0)
      fail(name_, line_, "vertex index 0 in 'f' line (OBJ indices start at 1)");
    const long long have = static_cast<long long>(verts_.size() / 3);
    if (vi < 0) {
      if (vi < -have)
        fail(name_, line_, "vertex index " + std::to_string(vi) + " out of range (only " +
                               std::to_string(have) + " vertices defined before this line)");
      return static_cast<std::uint32_t>(have + vi);
    }
    if (vi > 0xfffffffell)
      fail(name_, line_, "vertex index " + std::to_string(vi) + " out of range");
    if (vi > max_index_) {
      max_index_ = vi;
      max_index_line_ = line_;
    }
    return static_cast<std::uint32_t>(vi - 1);
  }

  void face(std::string_view rest) {
    const std::size_t start = index_.size();
    std::uint32_t n = 0;
    for (std::string_view tok = next_token(rest); !tok.empty(); tok = next_token(rest)) {
      if (tok[0] == '#') break;
      index_.push_back(vertex_ref(tok));
      ++n;
    }
    if (n < 3) {
      index_.resize(start);
      if (short_faces_++ == 0) short_line_ = line_;
      return;
    }
    if (polys_.size() >= static_cast<std::size_t>(INT_MAX))
      fail(name_, line_, "too many facets (more than " + std::to_string(INT_MAX) + ")");
    triangle_total_ += n - 2;
    if (triangle_total_ > kMaxTriangles)
      fail(name_, line_, "too many triangles (more than " + std::to_string(kMaxTriangles) + ")");
    polys_.push_back(Polygon{static_cast<std::uint32_t>(start), n, line_,
                             o_count_ > 0 ? o_count_ - 1 : 0, g_count_ > 0 ? g_count_ - 1 : 0,
                             slot_});
  }

  void usemtl(std::string_view rest) {
    // An empty name is legal: some exporters write "newmtl " and "usemtl ".
    const std::string name(trim(rest));
    auto it = slot_of_.find(name);
    if (it == slot_of_.end()) {
      it = slot_of_.emplace(name, static_cast<int>(slot_names_.size())).first;
      slot_names_.push_back(name);
      slot_lines_.push_back(line_);
    }
    slot_ = it->second;
  }

  void mtllib(std::string_view rest) {
    const std::string_view all = trim(rest);
    if (all.empty()) {
      warnings_.push_back(at(name_, line_) + "'mtllib' without a file name (ignored)");
      return;
    }
    if (base_dir_.empty()) {
      warnings_.push_back(at(name_, line_) + "'mtllib' ignored: material files are not read " +
                          "here; faces get the default material");
      return;
    }
    // A name with blanks is taken whole if such a file exists, else the line
    // is a list of names (both occur in the wild).
    std::vector<std::string> files;
    std::error_code ec;
    if (fs::is_regular_file(fs::path(base_dir_) / std::string(all), ec)) {
      files.emplace_back(all);
    } else {
      for (std::string_view r = all, t = next_token(r); !t.empty(); t = next_token(r))
        files.emplace_back(t);
    }
    for (const std::string& f : files) {
      const std::string path = (fs::path(base_dir_) / f).lexically_normal().string();
      if (!loaded_libs_.insert(path).second) continue;
      if (!fs::is_regular_file(path, ec)) {
        warnings_.push_back(at(name_, line_) + "material library '" + f + "' not found (" +
                            path + "); faces using its materials get the default material");
        continue;
      }
      const std::string text = read_input_file(path);
      for (MaterialDesc& m : parse_mtl(text, path, warnings_)) {
        if (lib_index_.count(m.name)) {
          if (++redefined_ <= kListedWarnings)
            warnings_.push_back(path + ": material '" + m.name +
                                "' is defined again; the first definition is used");
          continue;
        }
        lib_index_.emplace(m.name, static_cast<int>(library_.size()));
        library_.push_back(std::move(m));
      }
    }
  }

  Scene finish() {
    const long long nverts = static_cast<long long>(verts_.size() / 3);
    if (max_index_ > nverts) {
      // Name the first face (in file order) that is out of range.
      int line = max_index_line_;
      long long index = max_index_;
      bool found = false;
      for (std::size_t f = 0; f < polys_.size() && !found; ++f) {
        const Polygon& poly = polys_[f];
        for (std::uint32_t k = 0; k < poly.count && !found; ++k) {
          if (index_[poly.first + k] >= nverts) {
            line = poly.line;
            index = static_cast<long long>(index_[poly.first + k]) + 1;
            found = true;
          }
        }
      }
      fail(name_, line, "vertex index " + std::to_string(index) + " out of range (file has " +
                            std::to_string(nverts) + " vertices)");
    }
    Scene scene;
    scene.has_camera = false;
    scene.has_lights = false;
    if (polys_.empty()) {
      std::string why = name_ + ": no facets";
      if (short_faces_ > 0)
        why += " (" + std::to_string(short_faces_) + " faces with fewer than 3 vertices)";
      throw InputError(why);
    }

    // Materials: 0 is the SPEC default, then the MTL ones in definition order.
    scene.materials.push_back(MaterialDesc::default_material());
    for (const MaterialDesc& m : library_) scene.materials.push_back(m);
    std::vector<int> slot_material(slot_names_.size(), 0);
    int unknown = 0;
    for (std::size_t s = 0; s < slot_names_.size(); ++s) {
      auto it = lib_index_.find(slot_names_[s]);
      if (it != lib_index_.end()) {
        slot_material[s] = it->second + 1;
      } else if (++unknown <= kListedWarnings) {
        warnings_.push_back(at(name_, slot_lines_[s]) + "material '" + slot_names_[s] +
                            "' not found in any material library; its faces get the default "
                            "material");
      }
    }
    if (redefined_ > kListedWarnings)
      warnings_.push_back(name_ + ": " + std::to_string(redefined_ - kListedWarnings) +
                          " more materials defined twice; the first definitions are used");
    if (unknown > kListedWarnings)
      warnings_.push_back(name_ + ": " + std::to_string(unknown - kListedWarnings) +
                          " more unknown material names; their faces get the default material");

    const bool by_o = o_count_ > 0;
    scene.num_objects = by_o ? o_count_ : (g_count_ > 0 ? g_count_ : 1);
    scene.num_facets = static_cast<int>(polys_.size());

    scene.triangles.reserve(triangle_total_);
    int degenerate = 0, degenerate_line = 0;
    const auto vtx = [&](std::uint32_t i) {
      const float* p = &verts_[3 * static_cast<std::size_t>(i)];
      return Vec3{p[0], p[1], p[2]};
    };
    for (std::size_t f = 0; f < polys_.size(); ++f) {
      const Polygon& poly = polys_[f];
      const int object = by_o ? poly.section_o : (g_count_ > 0 ? poly.section_g : 0);
      const int material = poly.slot < 0 ? 0 : slot_material[poly.slot];
      const Vec3 p0 = vtx(index_[poly.first]);
      bool any = false;
      for (std::uint32_t k = 1; k + 1 < poly.count; ++k) {
        const Vec3 p1 = vtx(index_[poly.first + k]);
        const Vec3 p2 = vtx(index_[poly.first + k + 1]);
        // SPEC's geometric normal, in float: zero means no normal (skip it),
        // overflow means the renderer could not shade it (refuse the file).
        const float e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
        const float e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
        const float c[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                            e1[0] * e2[1] - e1[1] * e2[0]};
        if (!std::isfinite(c[0]) || !std::isfinite(c[1]) || !std::isfinite(c[2]))
          fail(name_, poly.line, "facet too large: its edge vectors overflow float");
        if (c[0] == 0 && c[1] == 0 && c[2] == 0) continue;
        Triangle t;
        t.v0 = p0;
        t.v1 = p1;
        t.v2 = p2;
        t.facet_id = static_cast<int>(f);
        t.object_id = object;
        t.material = material;
        scene.triangles.push_back(t);
        any = true;
      }
      if (!any && degenerate++ == 0) degenerate_line = poly.line;
    }
    if (scene.triangles.empty())
      throw InputError(name_ + ": no facets (all " + std::to_string(polys_.size()) +
                       " faces are degenerate)");

    if (short_faces_ > 0)
      warnings_.push_back(at(name_, short_line_) + "skipped " + std::to_string(short_faces_) +
                          " face(s) with fewer than 3 vertices (first on this line); they get "
                          "no facet id");
    if (degenerate > 0)
      warnings_.push_back(at(name_, degenerate_line) + std::to_string(degenerate) +
                          " degenerate (zero-area) facet(s) not rendered (first on this line); "
                          "they keep their facet ids");
    if (unknown_count_ > 0)
      warnings_.push_back(at(name_, unknown_line_) + "ignored " +
                          std::to_string(unknown_count_) + " line(s) with unknown statements "
                          "(first: " + quote(unknown_first_) + ")");

    check_scene_extent(scene, name_);
    Vec3 lo, hi;
    scene.bounds(lo, hi);
    scene.camera = frame_bounds(lo, hi, 45.0f, float(scene.width) / float(scene.height));
    scene.warnings = std::move(warnings_);
    return scene;
  }

  std::string_view text_;
  const std::string& name_;
  std::string base_dir_;
  int line_ = 0;

  std::vector<float> verts_;
  std::vector<std::uint32_t> index_;
  std::vector<Polygon> polys_;
  std::size_t triangle_total_ = 0;
  long long max_index_ = 0;
  int max_index_line_ = 0;
  int o_count_ = 0, g_count_ = 0;
  int short_faces_ = 0, short_line_ = 0;
  int unknown_count_ = 0, unknown_line_ = 0;
  std::string unknown_first_;

  int slot_ = -1;
  std::vector<std::string> slot_names_;
  std::vector<int> slot_lines_;
  std::unordered_map<std::string, int> slot_of_;

  // Warnings of one kind beyond this many are summed up in one line.
  static constexpr int kListedWarnings = 8;
  int redefined_ = 0;
  std::vector<MaterialDesc> library_;
  std::unordered_map<std::string, int> lib_index_;
  std::unordered_set<std::string> loaded_libs_;
  std::vector<std::string> warnings_;
};

Scene parse_guarded(std::string_view text, const std::string& name, const std::string& base_dir) {
  try {
    return ObjParser(text, name, base_dir).run();
  } catch (const std::bad_alloc&) {
    throw InputError(name + ": out of memory while loading (input too large)");
  } catch (const std::length_error&) {
    throw InputError(name + ": input too large to load");
  }
}

}  // namespace

Scene load_obj(const std::string& path) {
  const std::string text = read_input_file(path);
  std::string dir = fs::path(path).parent_path().string();
  if (dir.empty()) dir = ".";
  return parse_guarded(text, path, dir);
}

Scene load_obj_from_string(const std::string& text, const std::string& name,
                           const std::string& base_dir) {
  return parse_guarded(text, name, base_dir);
}

}  // namespace opsila
