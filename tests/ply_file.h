// PLY files for the tests: a header and its body, ascii or binary (either
// byte order), written from values.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

namespace opsila {
namespace test {

// A PLY file: its vertex properties (type, name), its vertices' values,
// its faces (index lists) and how they are written.
struct PlyFile {
  std::string format = "binary_little_endian";
  std::vector<std::pair<std::string, std::string>> props{{"float", "x"}, {"float", "y"}, {"float", "z"}};
  std::vector<std::vector<double>> vertices;
  std::string count_type = "uchar", index_type = "int", list_name = "vertex_indices";
  std::vector<std::vector<long long>> faces;
  std::string extra_header;  // lines before end_header
  std::uint64_t face_count = UINT64_MAX;  // the header's, when not faces.size()
  bool face_element = true;               // false: no 'face' element at all
  // A 'tristrips' element after the faces, one list a strip (-1 restarts),
  // when not empty; extra_strip_header follows its property line.
  std::vector<std::vector<long long>> strips;
  std::string strip_count_type = "int", extra_strip_header;
};

inline void put_ply_value(std::string& out, const std::string& type, double value, bool big) {
  unsigned char b[8];
  int n = 4;
  if (type == "float") { const float f = float(value); std::memcpy(b, &f, 4); }
  else if (type == "double") { std::memcpy(b, &value, 8); n = 8; }
  else if (type == "uchar" || type == "char") { const auto c = std::int8_t(value); std::memcpy(b, &c, 1); n = 1; }
  else if (type == "short" || type == "ushort") { const auto s = std::int16_t(value); std::memcpy(b, &s, 2); n = 2; }
  else { const auto i = std::int32_t(value); std::memcpy(b, &i, 4); }
  for (int k = 0; k < n; ++k) out += char(b[big ? n - 1 - k : k]);
}

inline void write_ply(const std::string& path, const PlyFile& p) {
  std::string out = "ply\nformat " + p.format + " 1.0\ncomment made by a test\n";
  out += "element vertex " + std::to_string(p.vertices.size()) + "\n";
  for (const auto& [type, name] : p.props) out += "property " + type + " " + name + "\n";
  if (p.face_element) {
    out += "element face " + std::to_string(p.face_count != UINT64_MAX ? p.face_count : p.faces.size()) + "\n";
    out += "property list " + p.count_type + " " + p.index_type + " " + p.list_name + "\n";
  }
  if (!p.strips.empty())
    out += "element tristrips " + std::to_string(p.strips.size()) + "\nproperty list " + p.strip_count_type + " " +
           p.index_type + " vertex_indices\n" + p.extra_strip_header;
  out += p.extra_header + "end_header\n";
  const bool ascii = p.format == "ascii", big = p.format == "binary_big_endian";
  const auto value = [&](const std::string& type, double v) {
    if (!ascii) return put_ply_value(out, type, v, big);
    char text[64];
    std::snprintf(text, sizeof text, type == "float" || type == "double" ? "%.9g " : "%.0f ", v);
    out += text;
  };
  for (const auto& v : p.vertices) {
    for (std::size_t k = 0; k < v.size(); ++k) value(p.props[k].first, v[k]);
    if (ascii) out.back() = '\n';
  }
  const auto lists = [&](const std::vector<std::vector<long long>>& all, const std::string& count_type) {
    for (const auto& f : all) {
      value(count_type, double(f.size()));
      for (long long i : f) value(p.index_type, double(i));
      if (ascii) out.back() = '\n';
    }
  };
  lists(p.faces, p.count_type);
  lists(p.strips, p.strip_count_type);
  std::ofstream(path, std::ios::binary) << out;
}

// A w x h grid of vertices (z a bump), as quads, with a pentagon, a
// triangle, a face of two corners and a degenerate one; `extra` values per
// vertex after x, y, z (normals, uv, colour) from the vertex's position.
inline PlyFile ply_grid(int w, int h, int extra) {
  PlyFile p;
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      std::vector<double> v{0.25 * i - 1.0 / 3.0, 0.5 * j + 0.1, std::sin(i * 0.7) * std::cos(j * 0.3)};
      for (int e = 0; e < extra; ++e) v.push_back(e == 2 ? 1.0 : std::fmod(0.37 * i + 0.11 * j + e * 0.19, 1.0));
      p.vertices.push_back(v);
    }
  for (int j = 0; j + 1 < h; ++j)
    for (int i = 0; i + 1 < w; ++i)
      p.faces.push_back({j * w + i, j * w + i + 1, (j + 1) * w + i + 1, (j + 1) * w + i});
  p.faces.push_back({0, 1, 2, w + 2, w});
  p.faces.push_back({w, w + 1, 1});
  p.faces.push_back({0, 1});
  p.faces.push_back({0, 1, 1});  // zero area
  return p;
}

// The strips of a w x h grid's rows (ply_grid's vertices): one list, a -1
// before each row but the last, which continues the row before it through
// repeated vertices (triangles that are no facets). `faces` gets the same
// triangles as a 'face' element lists them, each cell's two turned alike.
inline std::vector<std::vector<long long>> grid_strips(int w, int h, std::vector<std::vector<long long>>& faces) {
  std::vector<long long> strip;
  for (long long j = 0; j + 1 < h; ++j) {
    if (j > 0 && j + 2 < h) strip.push_back(-1);
    if (j > 0 && j + 2 == h) strip.push_back(strip.back()), strip.push_back(j * w);  // an even count: same parity
    for (long long i = 0; i < w; ++i) strip.push_back(j * w + i), strip.push_back((j + 1) * w + i);
    for (long long i = 0; i + 1 < w; ++i) {
      faces.push_back({j * w + i, (j + 1) * w + i, j * w + i + 1});
      faces.push_back({j * w + i + 1, (j + 1) * w + i, (j + 1) * w + i + 1});
    }
  }
  return {strip};
}

}  // namespace test
}  // namespace opsila
