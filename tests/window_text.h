// A scene read in windows (the OBJ, PLY and STL streams), as text to compare
// with one process's: each triangle bit for bit, the figures every rank
// must agree on, or the error.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "scene/scene.h"
#include "formats/assimp/model_import.h"
#include "formats/obj/obj_loader.h"
#include "test_util.h"

namespace opsila {
namespace test {

// A triangle with its attributes' values (indices differ between scenes).
inline std::string triangle_text(const Scene& s, const Triangle& t) {
  std::ostringstream o;
  for (const Vec3* v : {&t.v0, &t.v1, &t.v2}) o << hex((*v)[0]) << ' ' << hex((*v)[1]) << ' ' << hex((*v)[2]) << ' ';
  o << t.facet_id << ' ' << t.object_id << ' ' << t.material;
  if (t.attributes >= 0) {
    const VertexAttributes& a = s.attributes.at(std::size_t(t.attributes));
    o << " attr " << a.has_normals << a.has_uv;
    for (int c = 0; c < 3; ++c)
      o << ' ' << hex(a.normal[c][0]) << ' ' << hex(a.normal[c][1]) << ' ' << hex(a.normal[c][2]) << ' '
        << hex(a.uv[c][0]) << ' ' << hex(a.uv[c][1]);
  }
  return o.str();
}

// What every rank (or the one process) has besides its triangles.
inline std::string figures_text(const Scene& s, std::size_t triangles, const Vec3& lo, const Vec3& hi) {
  std::ostringstream o;
  o << "objects " << s.num_objects << " facets " << s.num_facets << " triangles " << triangles << "\n";
  o << "bounds " << hex(lo[0]) << ' ' << hex(lo[1]) << ' ' << hex(lo[2]) << ' ' << hex(hi[0]) << ' ' << hex(hi[1])
    << ' ' << hex(hi[2]) << "\n";
  for (const MaterialDesc& m : s.materials) o << "material " << m.name << ' ' << hex(m.kd[0]) << ' ' << m.map_kd << "\n";
  for (const std::string& w : s.warnings) o << "warning " << w << "\n";
  for (const std::string& f : s.input_files) o << "input " << f << "\n";
  o << "camera " << hex(s.camera.eye[0]) << ' ' << hex(s.camera.eye[1]) << ' ' << hex(s.camera.eye[2]) << "\n";
  return o.str();
}

inline std::string error_text(const InputError& e) {
  std::string o = "error " + std::string(e.what()) + "\n";
  for (const std::string& w : e.warnings) o += "warning " + w + "\n";
  return o;
}

// The model files of one format to try a stream on, sorted: every input of
// the fuzzing corpus whose first byte picks the format (fuzz_model.cpp: the
// byte mod 5 is `pick`), its text up to "#EXTERNAL#" written into `dir` as
// NAME.EXT; and the importer's test models of the format in `models` (when
// installed), copied there.
inline std::vector<std::string> corpus_models(const std::filesystem::path& dir, int pick, const std::string& ext,
                                              const std::filesystem::path& models) {
  namespace fs = std::filesystem;
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(fs::path(OPSILA_SOURCE_DIR) / "tests/fuzz/corpus_model")) {
    std::string bytes = read_file(entry.path().string());
    if (bytes.empty() || static_cast<unsigned char>(bytes[0]) % 5 != pick) continue;
    bytes = bytes.substr(1, bytes.find("#EXTERNAL#") - 1);
    const std::string path = (dir / (entry.path().filename().string() + "." + ext)).string();
    std::ofstream(path, std::ios::binary) << bytes;
    files.push_back(path);
  }
  if (fs::is_directory(models))
    for (const auto& entry : fs::directory_iterator(models)) {
      if (!entry.is_regular_file()) continue;
      const std::string path = (dir / entry.path().filename()).string();
      fs::copy_file(entry.path(), path, fs::copy_options::overwrite_existing);
      files.push_back(path);
    }
  std::sort(files.begin(), files.end());
  return files;
}

// One process's scene as `load` reads it: its figures, then its
// triangles; or its error.
inline std::string loaded_text(const std::function<Scene()>& load) {
  try {
    const Scene s = load();
    Vec3 lo, hi;
    s.bounds(lo, hi);
    std::string o = figures_text(s, s.triangles.size(), lo, hi);
    for (const Triangle& t : s.triangles) o += triangle_text(s, t) + "\n";
    return o;
  } catch (const InputError& e) {
    return error_text(e);
  }
}

// One process's import of a model file (model_import.cpp), as windows_text
// gives the windows of the same file.
inline std::string imported_text(const std::string& path) {
  return loaded_text([&] { return load_model(path); });
}

// R ranks, each reading the file twice with `load` (first counting, with no
// window, then keeping its window): each one's figures (which must agree),
// then the windows' triangles in rank order; the spread objects each rank
// names must be those whose triangles lie on several ranks.
inline std::string windows_text(int R, const std::function<Scene(const ModelWindow&, std::uint64_t&)>& load) {
  std::string figures, triangles;
  std::vector<std::set<int>> holders;  // by object: ranks holding its triangles
  std::vector<int> spread;
  for (int r = 0; r < R; ++r) {
    try {
      ModelWindow w;
      w.rank = r, w.ranks = R;
      w.load_maps = false;
      std::uint64_t fans = 0;
      const Scene counted = load(w, fans);
      EXPECT_TRUE(counted.triangles.empty()) << "the counting read keeps nothing";
      w.plan_all = w.plan_total = counted.share.total_triangles;
      w.fans = fans;
      w.load_maps = true;
      const Scene s = load(w, fans);
      const std::string mine = figures_text(s, s.share.total_triangles, s.share.lo, s.share.hi);
      if (r == 0) figures = mine, spread = s.share.spread;
      EXPECT_EQ(mine, figures) << "rank " << r << " agrees with rank 0";
      EXPECT_EQ(s.share.spread, spread) << "rank " << r;
      for (const Triangle& t : s.triangles) {
        triangles += triangle_text(s, t) + "\n";
        if (holders.size() <= std::size_t(t.object_id)) holders.resize(std::size_t(t.object_id) + 1);
        holders[std::size_t(t.object_id)].insert(r);
      }
    } catch (const InputError& e) {
      const std::string mine = error_text(e);
      if (r == 0) figures = mine;
      EXPECT_EQ(mine, figures) << "rank " << r << " fails as rank 0 does";
    }
  }
  std::vector<int> several;
  for (std::size_t o = 0; o < holders.size(); ++o)
    if (holders[o].size() > 1) several.push_back(static_cast<int>(o));
  EXPECT_EQ(spread, several) << "spread: the objects whose triangles lie on several ranks";
  return figures + triangles;
}

}  // namespace test
}  // namespace opsila
