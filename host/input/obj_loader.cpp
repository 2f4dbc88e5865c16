// Strict OBJ/MTL scanning (MTL: mtl_parser.cpp; the shared scanning:
// obj_text.cpp). Geometry and materials are parsed here rather than
// with tinyobjloader: it turns non-numbers into 0, reads "Ks 0.5" as
// (0.5, 0, 0) and reports no line numbers, and the project promises one
// precise FILE:LINE message for every bad input.
#include "input/obj_loader.h"

#include "core/stage_clock.h"
#include "input/obj_text.h"
#include "input/texture_file.h"

#include <cerrno>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>
#include <new>
#include <stdexcept>
#include <string_view>
#include <system_error>
#include <unordered_map>
#include <unordered_set>

namespace opsila {

namespace fs = std::filesystem;

using namespace obj_text;

// ---------------------------------------------------------------- OBJ -----

namespace {

// Statements of the OBJ specification that do not change the image.
bool is_ignored_obj_statement(std::string_view kw) {
  static const char* const names[] = {
      "vp", "l", "p", "s", "mg", "cstype", "deg", "bmat", "step", "curv",
      "curv2", "surf", "parm", "trim", "hole", "scrv", "sp", "end", "con", "bevel",
      "c_interp", "d_interp", "lod", "maplib", "usemap", "shadow_obj", "trace_obj",
      "ctech", "stech", "call", "csh"};
  for (const char* n : names)
    if (kw == n) return true;
  return false;
}

struct Polygon {
  std::uint32_t first;  // into the flat index lists
  std::uint32_t count;
  int line;
  int section_o, section_g;  // 0-based index of the o / g section (clamped)
  int slot;                  // usemtl slot, -1 = no material
  bool has_uv, has_normals;  // every corner names a vt (vn)
};

constexpr std::uint32_t kNoIndex = 0xffffffffu;

// One kind of indexed list (v, vt or vn): its size so far and the largest
// positive index named, which may lie further down the file.
struct IndexedList {
  const char* what;
  std::vector<float> values;
  int width;  // floats per entry
  long long max_index = 0;
  int max_line = 0;
  bool strict;           // a bad index is an error (v), else a warning (vt, vn)
  int missing = 0, missing_line = 0;  // corners whose index names nothing (not strict)
  long long size() const { return static_cast<long long>(values.size() / width); }
};

class ObjParser {
 public:
  ObjParser(std::string_view text, const std::string& name, const std::string& base_dir,
            std::size_t max_triangles, StageClock* clock)
      : text_(text), name_(name), base_dir_(base_dir), max_triangles_(max_triangles), clock_(clock) {}

  std::vector<std::string>& warnings() { return warnings_; }

  Scene run() {
    if (text_.size() > kMaxInputFileBytes)
      throw InputError(name_ + ": input too large (" + std::to_string(text_.size()) + " bytes)");
    LineScanner sc(text_, name_);
    std::string_view line;
    while (sc.next(line)) {
      line_ = sc.line_no();
      if (clock_ && (line_ & 0xffff) == 0) clock_->progress(double(line.data() - text_.data()) / double(text_.size()));
      std::string_view rest = line;
      const std::string_view kw = next_token(rest);
      if (kw.empty() || kw[0] == '#') continue;
      if (kw == "v") {
        vertex(rest);
      } else if (kw == "f") {
        face(rest);
      } else if (kw == "vt") {
        attribute(rest, uvs_, "vt", 1, 3);
      } else if (kw == "vn") {
        attribute(rest, normals_, "vn", 3, 3);
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
    verts_.values.insert(verts_.values.end(), xyz, xyz + 3);
  }

  // "vt u [v [w]]" (v defaults to 0) and "vn x y z".
  void attribute(std::string_view rest, IndexedList& list, const char* key, int min_n, int max_n) {
    float xyz[3] = {0, 0, 0};
    int n = 0;
    for (std::string_view tok = next_token(rest); !tok.empty(); tok = next_token(rest)) {
      if (tok[0] == '#') break;
      float x;
      const Num s = parse_float(tok, x);
      if (s != Num::ok)
        fail(name_, line_, std::string("'") + key + "' value " + std::to_string(n + 1) + " " + quote(tok) + " " +
                               describe(s));
      if (n == max_n)
        fail(name_, line_, std::string("'") + key + "' line has more than " + std::to_string(max_n) + " values");
      xyz[n++] = x;
    }
    if (n < min_n)
      fail(name_, line_, std::string("truncated '") + key + "' line: " + std::to_string(n) + " of " +
                             std::to_string(min_n) + " values");
    list.values.insert(list.values.end(), xyz, xyz + list.width);
  }

  // One index of a face corner into `list`, 0-based. Negative indices count
  // back from the entries defined so far; positive ones are range-checked at
  // the end of the file.
  std::uint32_t index_into(IndexedList& list, long long i, std::string_view tok) {
    if (i == 0)
      fail(name_, line_, std::string(list.what) + " index 0 in " + quote(tok) + " (OBJ indices start at 1)");
    const long long have = list.size();
    if (i < 0) {
      if (i < -have && !list.strict) {
        if (list.missing++ == 0) list.missing_line = line_;
        return kNoIndex;
      }
      if (i < -have)
        fail(name_, line_, std::string(list.what) + " index " + std::to_string(i) + " out of range (only " +
                               std::to_string(have) + " defined before this line)");
      return static_cast<std::uint32_t>(have + i);
    }
    if (i > 0xfffffffell) fail(name_, line_, std::string(list.what) + " index " + std::to_string(i) + " out of range");
    if (i > list.max_index) {
      list.max_index = i;
      list.max_line = line_;
    }
    return static_cast<std::uint32_t>(i - 1);
  }

  // One "v", "v/vt", "v//vn" or "v/vt/vn" reference.
  void vertex_ref(std::string_view tok, std::uint32_t& v, std::uint32_t& vt, std::uint32_t& vn) {
    const std::size_t s1 = tok.find('/');
    const std::string_view vpart = tok.substr(0, s1);
    std::string_view tpart, npart;
    bool ok = true;
    long long vi = 0, ti = 0, ni = 0;
    if (s1 != std::string_view::npos) {
      std::string_view tail = tok.substr(s1 + 1);
      const std::size_t s2 = tail.find('/');
      tpart = tail.substr(0, s2);
      if (s2 == std::string_view::npos) {
        ok = parse_int(tpart, ti) && ti != 0;  // v/vt
      } else {
        npart = tail.substr(s2 + 1);
        ok = (tpart.empty() || (parse_int(tpart, ti) && ti != 0)) && parse_int(npart, ni) &&
             ni != 0;  // v//vn or v/vt/vn
      }
    }
    if (!ok || !parse_int(vpart, vi))
      fail(name_, line_, "bad vertex reference " + quote(tok) +
                             " in 'f' line (expected v, v/vt, v//vn or v/vt/vn with non-zero "
                             "integers)");
    if (vi == 0)
      fail(name_, line_, "vertex index 0 in 'f' line (OBJ indices start at 1)");
    v = index_into(verts_, vi, tok);
    vt = ti != 0 ? index_into(uvs_, ti, tok) : kNoIndex;
    vn = ni != 0 ? index_into(normals_, ni, tok) : kNoIndex;
  }

  void face(std::string_view rest) {
    const std::size_t start = index_.size();
    std::uint32_t n = 0;
    bool all_uv = true, all_normals = true;
    for (std::string_view tok = next_token(rest); !tok.empty(); tok = next_token(rest)) {
      if (tok[0] == '#') break;
      std::uint32_t v, vt, vn;
      vertex_ref(tok, v, vt, vn);
      index_.push_back(v);
      uv_index_.push_back(vt);
      normal_index_.push_back(vn);
      all_uv = all_uv && vt != kNoIndex;
      all_normals = all_normals && vn != kNoIndex;
      ++n;
    }
    if (n < 3) {
      index_.resize(start);
      uv_index_.resize(start);
      normal_index_.resize(start);
      if (short_faces_++ == 0) short_line_ = line_;
      return;
    }
    if (polys_.size() >= static_cast<std::size_t>(INT_MAX))
      fail(name_, line_, "too many facets (more than " + std::to_string(INT_MAX) + ")");
    triangle_total_ += n - 2;
    if (triangle_total_ > max_triangles_)
      fail(name_, line_, "too many triangles (more than " + std::to_string(max_triangles_) +
                             ", scenes/FORMAT.md, Limits)");
    polys_.push_back(Polygon{static_cast<std::uint32_t>(start), n, line_,
                             o_count_ > 0 ? o_count_ - 1 : 0, g_count_ > 0 ? g_count_ - 1 : 0,
                             slot_, all_uv, all_normals});
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
        warnings_.push_back(at(name_, line_) + "material library " + quote(f) + " not found (" +
                            quote(path) + "); faces using its materials get the default material");
        continue;
      }
      const std::string text = read_text_file(path);
      input_files_.push_back(path);
      for (MaterialDesc& m : parse_mtl(text, path, warnings_)) {
        if (lib_index_.count(m.name)) {
          if (++redefined_ <= kListedWarnings)
            warnings_.push_back(path + ": material " + quote(m.name) +
                                " is defined again; the first definition is used");
          continue;
        }
        lib_index_.emplace(m.name, static_cast<int>(library_.size()));
        const std::string mtl_dir = fs::path(path).parent_path().string();
        if (!m.map_kd_file.empty()) m.map_kd_file = resolve_texture_path(m.map_kd_file, mtl_dir);
        if (!m.map_ka_file.empty()) m.map_ka_file = resolve_texture_path(m.map_ka_file, mtl_dir);
        library_.push_back(std::move(m));
        library_file_.push_back(path);
      }
    }
  }

  // A positive index past the end of its list: name the first face (in file
  // order) that has one.
  void check_range(IndexedList& list, const std::vector<std::uint32_t>& index, const char* plural) {
    const long long have = list.size();
    if (!list.strict) {
      // Texture coordinates and normals that do not exist: the face gets none
      // (files that name them without defining them do occur).
      for (Polygon& poly : polys_) {
        bool& has = &list == &uvs_ ? poly.has_uv : poly.has_normals;
        for (std::uint32_t k = 0; k < poly.count && has; ++k) {
          const std::uint32_t i = index[poly.first + k];
          if (i == kNoIndex || i >= have) {
            if (list.missing++ == 0 || poly.line < list.missing_line) list.missing_line = poly.line;
            has = false;
          }
        }
      }
      if (list.missing > 0)
        warnings_.push_back(at(name_, list.missing_line) + std::to_string(list.missing) + " face corner(s) name " +
                            plural + " the file does not define (first on this line); those faces get none");
      return;
    }
    if (list.max_index <= have) return;
    int line = list.max_line;
    long long bad = list.max_index;
    bool found = false;
    for (std::size_t f = 0; f < polys_.size() && !found; ++f) {
      const Polygon& poly = polys_[f];
      for (std::uint32_t k = 0; k < poly.count && !found; ++k) {
        const std::uint32_t i = index[poly.first + k];
        if (i != kNoIndex && i >= have) {
          line = poly.line;
          bad = static_cast<long long>(i) + 1;
          found = true;
        }
      }
    }
    fail(name_, line, std::string(list.what) + " index " + std::to_string(bad) + " out of range (file has " +
                          std::to_string(have) + " " + plural + ")");
  }

  // Texture maps of the library materials that faces with texture
  // coordinates use (others could not show them), loaded once each; an image
  // that cannot be read is a warning and its map is ignored.
  void load_maps(Scene& scene, const std::vector<int>& slot_material) {
    std::vector<char> mapped(library_.size() + 1, 0);
    for (const Polygon& poly : polys_)
      if (poly.has_uv && poly.slot >= 0) mapped[slot_material[poly.slot]] = 1;
    for (std::size_t k = 0; k < library_.size(); ++k) {
      if (!mapped[k + 1]) continue;
      MaterialDesc& m = scene.materials[k + 1];
      const std::string where = library_file_[k] + ": material '" + m.name + "': ";
      if (!m.map_kd_file.empty()) m.map_kd = add_texture_file(scene, m.map_kd_file, where);
      if (!m.map_ka_file.empty()) m.map_ka = add_texture_file(scene, m.map_ka_file, where);
    }
  }

  // The corners of fan triangle (0, k, k + 1) of a polygon, as attributes.
  int add_attributes(Scene& scene, const Polygon& poly, std::uint32_t k) const {
    if (!poly.has_uv && !poly.has_normals) return -1;
    VertexAttributes a;
    const std::uint32_t corner[3] = {poly.first, poly.first + k, poly.first + k + 1};
    for (int c = 0; c < 3; ++c) {
      if (poly.has_normals) {
        const float* n = &normals_.values[3 * static_cast<std::size_t>(normal_index_[corner[c]])];
        a.normal[c] = Vec3{n[0], n[1], n[2]};
      }
      if (poly.has_uv) {
        const float* t = &uvs_.values[2 * static_cast<std::size_t>(uv_index_[corner[c]])];
        a.uv[c] = {t[0], t[1]};
      }
    }
    a.has_normals = poly.has_normals;
    a.has_uv = poly.has_uv;
    scene.attributes.push_back(a);
    return static_cast<int>(scene.attributes.size()) - 1;
  }

  Scene finish() {
    check_range(verts_, index_, "vertices");
    check_range(uvs_, uv_index_, "texture coordinates");
    check_range(normals_, normal_index_, "normals");
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
        warnings_.push_back(at(name_, slot_lines_[s]) + "material " + quote(slot_names_[s]) +
                            " not found in any material library; its faces get the default "
                            "material");
      }
    }
    load_maps(scene, slot_material);
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
      const float* p = &verts_.values[3 * static_cast<std::size_t>(i)];
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
        t.attributes = add_attributes(scene, poly, k);
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
    for (std::string& w : scene.warnings) warnings_.push_back(std::move(w));
    scene.warnings = std::move(warnings_);
    scene.input_files.insert(scene.input_files.begin(), input_files_.begin(), input_files_.end());
    return scene;
  }

  std::string_view text_;
  const std::string& name_;
  std::string base_dir_;
  std::size_t max_triangles_;
  StageClock* clock_;
  int line_ = 0;

  IndexedList verts_{"vertex", {}, 3, 0, 0, true};
  IndexedList uvs_{"texture coordinate", {}, 2, 0, 0, false};
  IndexedList normals_{"normal", {}, 3, 0, 0, false};
  // Per face corner: v, vt and vn (kNoIndex when the corner names none).
  std::vector<std::uint32_t> index_, uv_index_, normal_index_;
  std::vector<Polygon> polys_;
  std::size_t triangle_total_ = 0;
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
  std::vector<std::string> library_file_;  // the MTL file each material came from
  std::unordered_map<std::string, int> lib_index_;
  std::unordered_set<std::string> loaded_libs_;
  std::vector<std::string> warnings_;
  std::vector<std::string> input_files_;  // material libraries read
};

Scene parse_guarded(std::string_view text, const std::string& name, const std::string& base_dir,
                    std::size_t max_triangles, StageClock* clock = nullptr) {
  ObjParser parser(text, name, base_dir, max_triangles, clock);
  try {
    return parser.run();
  } catch (InputError& e) {
    e.warnings = std::move(parser.warnings());  // found before the error: still shown
    throw;
  } catch (const std::bad_alloc&) {
    throw InputError(name + ": out of memory while loading (input too large)");
  } catch (const std::length_error&) {
    throw InputError(name + ": input too large to load");
  }
}

}  // namespace

Scene load_obj(const std::string& path, std::size_t max_triangles) {
  const std::string text = read_text_file(path);
  std::string dir = fs::path(path).parent_path().string();
  if (dir.empty()) dir = ".";
  StageClock clock(PrepareStage::parse);
  Scene scene = parse_guarded(text, path, dir, max_triangles, &clock);
  scene.input_files.insert(scene.input_files.begin(), path);
  return scene;
}

Scene load_obj_from_string(const std::string& text, const std::string& name,
                           const std::string& base_dir) {
  return parse_guarded(text, name, base_dir, kMaxTriangles);
}

}  // namespace opsila
