// Strict MTL reading: the material keys CONTRACT uses, each value checked and
// every problem named by FILE:LINE.
#include "formats/obj/obj_loader.h"

#include <array>
#include <algorithm>
#include <iterator>
#include <string>
#include <string_view>
#include <vector>

#include "formats/obj/obj_text.h"

namespace opsila {

using namespace obj_text;

namespace {

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

// The file of a map statement ("map_Kd [-options] file"): options and their
// values are skipped; the rest of the line, blanks included, is the file.
// Options that change the mapping (-o, -s, -t, -clamp on) are not part of
// CONTRACT's texture lookup: they are ignored with a warning.
std::string map_file(std::string_view rest, std::string_view key, const std::string& file, int line,
                     std::vector<std::string>& warnings) {
  std::vector<std::string> ignored;
  for (;;) {
    std::string_view probe = rest;
    const std::string_view tok = next_token(probe);
    if (tok.size() < 2 || tok[0] != '-') break;
    float number;
    if (parse_float(tok, number) == Num::ok) break;  // "-1.png" is a name
    // Only the options MTL defines are options: "-tex.png" is a name (it had
    // been skipped as an option, and the map lost).
    static const char* const kOptions[] = {"-blendu", "-blendv", "-boost", "-mm",  "-o",    "-s",   "-t",
                                           "-texres", "-clamp",  "-bm",    "-imfchan", "-type", "-cc"};
    if (std::none_of(std::begin(kOptions), std::end(kOptions), [&](const char* o) { return tok == o; })) break;
    rest = probe;
    const std::string opt(tok);
    int min_args = 1, max_args = 1;
    if (opt == "-o" || opt == "-s" || opt == "-t") min_args = 1, max_args = 3;
    else if (opt == "-mm") min_args = max_args = 2;
    for (int k = 0; k < max_args; ++k) {
      probe = rest;
      const std::string_view arg = next_token(probe);
      const bool numeric = parse_float(arg, number) == Num::ok;
      if (k >= min_args && !numeric) break;
      if (arg.empty()) break;
      rest = probe;
      if (opt == "-clamp" && arg == "on") ignored.push_back("-clamp on");
    }
    if (opt == "-o" || opt == "-s" || opt == "-t") ignored.push_back(opt);
  }
  const std::string name(trim(rest));
  if (!ignored.empty()) {
    std::string list;
    for (const std::string& o : ignored) list += (list.empty() ? "" : ", ") + o;
    warnings.push_back(at(file, line) + "'" + std::string(key) + "' option(s) " + list +
                       " ignored (texture coordinates are used as they are)");
  }
  if (name.empty()) warnings.push_back(at(file, line) + "'" + std::string(key) + "' without a file name (ignored)");
  return name;
}

}  // namespace

std::vector<MaterialDesc> parse_mtl(const std::string& text, const std::string& name,
                                    std::vector<std::string>& warnings) {
  std::vector<MaterialDesc> out;
  std::vector<std::array<bool, 2>> given;  // per material: Ka, Kd stated
  LineScanner sc(text, name);
  std::string_view line;
  int orphan_keys = 0, orphan_line = 0;
  while (sc.next(line)) {
    const int ln = sc.line_no();
    std::string_view rest = line;
    const std::string_view kw = next_token(rest);
    if (kw.empty() || kw[0] == '#') continue;
    if (kw == "newmtl") {
      check_material_count(out.size() + 2, at(name, ln) + "'newmtl': ");  // the default is the scene's first
      MaterialDesc m;  // CONTRACT defaults for keys left out
      m.name = std::string(trim(rest));
      out.push_back(std::move(m));
      given.push_back({false, false});
      continue;
    }
    const bool known = kw == "Ka" || kw == "Kd" || kw == "Ks" || kw == "Tf" || kw == "Ns" ||
                       kw == "Ni" || kw == "illum" || kw == "map_Kd" || kw == "map_Ka";
    if (!known) {
      if (!is_identifier(kw)) fail(name, ln, "invalid statement " + quote(kw) + " (binary file?)");
      continue;  // d, Tr, Ke, map_Ks, bump, ...: no effect on the image
    }
    if (out.empty()) {
      if (orphan_keys++ == 0) orphan_line = ln;
      continue;
    }
    MaterialDesc& m = out.back();
    if (kw == "map_Kd" || kw == "map_Ka") {
      (kw == "map_Kd" ? m.map_kd_file : m.map_ka_file) = map_file(rest, kw, name, ln, warnings);
    } else if (kw == "Ka" || kw == "Kd" || kw == "Ks" || kw == "Tf") {
      if (kw == "Ka" || kw == "Kd") given.back()[kw == "Kd"] = true;
      std::string_view probe = rest;
      const std::string_view first = next_token(probe);
      if (first == "spectral" || first == "xyz") {
        warnings.push_back(at(name, ln) + "'" + std::string(kw) + " " + std::string(first) +
                           "' is not supported (only RGB); material " + quote(m.name) + " keeps " +
                           std::string(kw) + " = 0");
        continue;
      }
      Vec3& c = kw == "Ka" ? m.ka : kw == "Kd" ? m.kd : kw == "Ks" ? m.ks : m.tf;
      parse_colour(rest, kw, name, ln, c);
      for (float x : c)
        if (const std::string why = material_value_problem(std::string(kw), x); !why.empty())
          fail(name, ln, "'" + std::string(kw) + "' " + why);
    } else if (kw == "Ns") {
      m.ns = parse_single(rest, kw, name, ln);
      if (const std::string why = material_value_problem("Ns", m.ns); !why.empty())
        fail(name, ln, "'Ns' " + why);
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
  for (std::size_t k = 0; k < out.size(); ++k) {
    MaterialDesc& m = out[k];
    // A map is known by its statement, read or not (CONTRACT: the colour is the
    // texture's alone; an image that cannot be read is then ignored).
    if (!given[k][0]) m.ka = left_out_colour(!m.map_ka_file.empty());
    if (!given[k][1]) m.kd = left_out_colour(!m.map_kd_file.empty());
    if (illum_transmits(m.illum) && !(m.ni > 0))
      warnings.push_back(name + ": material " + quote(m.name) +
                         " transmits light but has Ni <= 0 (refraction is undefined)");
  }
  return out;
}

}  // namespace opsila
