// Strict OBJ/MTL scanning (MTL: mtl_parser.cpp; the shared scanning:
// obj_text.cpp; the statements: obj_statements.cpp; chunks read in
// parallel: obj_chunks.cpp). Geometry and materials are parsed here rather
// than with tinyobjloader: it turns non-numbers into 0, reads "Ks 0.5" as
// (0.5, 0, 0) and reports no line numbers, and the project promises one
// precise FILE:LINE message for every bad input.
#include "formats/obj/obj_loader.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <new>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "core/parallel.h"
#include "core/stage_clock.h"
#include "formats/obj/obj_parser.h"
#include "formats/obj/obj_text.h"
#include "formats/image/texture_file.h"

namespace opsila {

namespace fs = std::filesystem;

using namespace obj_text;

namespace obj_parse {

namespace {

// Faces that name texture coordinates (or normals) on some corners only:
// the OBJ specification gives every corner of a face one form, and such a
// face is drawn without them; one warning for each kind says so.
void warn_mixed_corners(const std::vector<Polygon>& polys, const std::vector<std::uint32_t>& uv,
                        const std::vector<std::uint32_t>& normals, const std::string& name,
                        std::vector<std::string>& warnings) {
  for (const bool of_uv : {true, false}) {
    const std::vector<std::uint32_t>& index = of_uv ? uv : normals;
    std::size_t count = 0;
    int line = 0;
    for (const Polygon& p : polys) {
      if (of_uv ? p.has_uv : p.has_normals) continue;
      bool some = false;
      for (std::uint32_t c = 0; c < p.count && !some; ++c) some = index[p.first + c] != kNoIndex;
      if (some && count++ == 0) line = p.line;
    }
    if (count > 0)
      warnings.push_back(at(name, line) + std::to_string(count) + " face(s) name " +
                         (of_uv ? "texture coordinates" : "normals") +
                         " on some corners only (first on this line): they are drawn without them");
  }
}

}  // namespace

// A positive index past the end of its list: name the first face (in file
// order) that has one.
void ObjParser::check_range(IndexedList& list, const std::vector<std::uint32_t>& index, const char* plural) {
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
void ObjParser::load_maps(Scene& scene, const std::vector<int>& slot_material) {
  if (win_ && !win_->plan.load_maps) return;
  const MapImages images = win_ ? win_->plan.map_images : MapImages::now;
  std::vector<char> mapped(library_.size() + 1, 0);
  for (const Polygon& poly : polys_)
    if (poly.has_uv && poly.slot >= 0) mapped[slot_material[poly.slot]] = 1;
  if (win_)  // faces let go while streaming (their indices were all defined)
    for (std::size_t s = 0; s < win_->mapped_slot.size(); ++s)
      if (win_->mapped_slot[s]) mapped[slot_material[s]] = 1;
  for (std::size_t k = 0; k < library_.size(); ++k) {
    if (!mapped[k + 1]) continue;
    MaterialDesc& m = scene.materials[k + 1];
    const std::string where = library_file_[k] + ": material '" + m.name + "': ";
    if (!m.map_kd_file.empty()) m.map_kd = add_texture_file(scene, m.map_kd_file, where, images);
    if (!m.map_ka_file.empty()) m.map_ka = add_texture_file(scene, m.map_ka_file, where, images);
  }
}


// The corners of fan triangle (0, k, k + 1) of a polygon, as attributes.
int ObjParser::add_attributes(Scene& scene, const Polygon& poly, std::uint32_t k) const {
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

// Materials: 0 is the CONTRACT default, then the MTL ones in definition order;
// a slot whose name no library defines gets the default (and a warning).
std::vector<int> ObjParser::resolve_materials(Scene& scene) {
  scene.materials.push_back(MaterialDesc::default_material());
  for (const MaterialDesc& m : library_) scene.materials.push_back(m);
  check_material_count(scene.materials.size(), name_ + ": its material libraries: ");
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

  return slot_material;
}

// Polygon `id` fanned into triangles (0, k, k + 1) from its first vertex,
// counted into `fig` and, unless `out` is null, appended to it. A zero-area
// triangle is skipped (a face with none left is degenerate, its id kept);
// one whose normal overflows float is noted (the file is refused). True
// when the face has a triangle.
bool ObjParser::fan(const Polygon& poly, int id, FanFigures& fig, Scene* out, int object, int material) const {
  const auto vtx = [&](std::uint32_t i) {
    const float* p = &verts_.values[3 * static_cast<std::size_t>(i)];
    return Vec3{p[0], p[1], p[2]};
  };
  const Vec3 p0 = vtx(index_[poly.first]);
  bool any = false;
  for (std::uint32_t k = 1; k + 1 < poly.count; ++k) {
    const Vec3 p1 = vtx(index_[poly.first + k]);
    const Vec3 p2 = vtx(index_[poly.first + k + 1]);
    // CONTRACT's geometric normal, in float: zero means no normal (skip it),
    // overflow means the renderer could not shade it (refuse the file).
    const float e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
    const float e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
    const float c[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                        e1[0] * e2[1] - e1[1] * e2[0]};
    if (!std::isfinite(c[0]) || !std::isfinite(c[1]) || !std::isfinite(c[2])) {
      if (fig.overflow_id < 0 || id < fig.overflow_id) fig.overflow_id = id, fig.overflow_line = poly.line;
      continue;
    }
    if (c[0] == 0 && c[1] == 0 && c[2] == 0) continue;
    ++fig.triangles;
    for (int a = 0; a < 3; ++a) {
      fig.lo[a] = std::min({fig.lo[a], p0[a], p1[a], p2[a]});
      fig.hi[a] = std::max({fig.hi[a], p0[a], p1[a], p2[a]});
    }
    any = true;
    if (!out) continue;
    Triangle t;
    t.v0 = p0;
    t.v1 = p1;
    t.v2 = p2;
    t.facet_id = id;
    t.fan = static_cast<int>(k - 1);
    t.object_id = object;
    t.material = material;
    t.attributes = add_attributes(*out, poly, k);
    out->triangles.push_back(t);
  }
  if (!any && (fig.degenerate++ == 0 || poly.line < fig.degenerate_line)) fig.degenerate_line = poly.line;
  return any;
}

// Each face (a window's: those kept) fanned into triangles; a window's
// figures start from the faces it let go, and only its own are appended.
FanFigures ObjParser::triangulate(Scene& scene, const std::vector<int>& slot_material) {
  FanFigures fig = win_ ? win_->let_go : FanFigures{};
  if (!win_) scene.triangles.reserve(triangle_total_);
  const bool by_o = o_count_ > 0;
  for (std::size_t f = 0; f < polys_.size(); ++f) {
    const Polygon& poly = polys_[f];
    const int object = std::max(0, (by_o ? poly.o_seen : g_count_ > 0 ? poly.g_seen : 1) - 1);
    const int material = poly.slot < 0 ? 0 : slot_material[poly.slot];
    const int owner = win_ ? win_->owner[f] : 0;
    const bool mine = !win_ || (owner >= 0 && owner == win_->plan.rank);
    const bool any = fan(poly, win_ ? win_->id[f] : static_cast<int>(f), fig, mine ? &scene : nullptr, object, material);
    if (any && win_) win_->note(poly, owner);
  }
  return fig;
}

Scene ObjParser::finish() {
  check_range(verts_, index_, "vertices");
  check_range(uvs_, uv_index_, "texture coordinates");
  check_range(normals_, normal_index_, "normals");
  Scene scene;
  scene.has_camera = false;
  scene.has_lights = false;
  const std::size_t polygon_count = polygons();
  if (polygon_count == 0) {
    std::string why = name_ + ": no facets";
    if (short_faces_ > 0)
      why += " (" + std::to_string(short_faces_) + " faces with fewer than 3 vertices)";
    throw InputError(why);
  }

  const std::vector<int> slot_material = resolve_materials(scene);
  scene.num_objects = o_count_ > 0 ? o_count_ : (g_count_ > 0 ? g_count_ : 1);
  scene.num_facets = static_cast<int>(polygon_count);
  const FanFigures fig = triangulate(scene, slot_material);
  if (fig.overflow_id >= 0) fail(name_, fig.overflow_line, "facet too large: its edge vectors overflow float");
  if (fig.triangles == 0)
    throw InputError(name_ + ": no facets (all " + std::to_string(polygon_count) + " faces are degenerate)");

  if (short_faces_ > 0)
    warnings_.push_back(at(name_, short_line_) + "skipped " + std::to_string(short_faces_) +
                        " face(s) with fewer than 3 vertices (first on this line); they get "
                        "no facet id");
  if (fig.degenerate > 0)
    warnings_.push_back(at(name_, fig.degenerate_line) + std::to_string(fig.degenerate) +
                        " degenerate (zero-area) facet(s) not rendered (first on this line); "
                        "they keep their facet ids");
  if (unknown_count_ > 0)
    warnings_.push_back(at(name_, unknown_line_) + "ignored " +
                        std::to_string(unknown_count_) + " line(s) with unknown statements "
                        "(first: " + quote(unknown_first_) + ")");
  warn_mixed_corners(polys_, uv_index_, normal_index_, name_, warnings_);

  // A window's extent is the whole file's, which every rank has counted.
  Vec3 lo = fig.lo, hi = fig.hi;
  if (win_) window_share(scene, fig);
  else scene.bounds(lo, hi);
  check_scene_extent(win_ ? fig.triangles : scene.triangles.size(), lo, hi, name_);
  scene.camera = frame_bounds(lo, hi, 45.0f, float(scene.width) / float(scene.height));
  put_warnings_first(scene, std::move(warnings_));
  scene.input_files.insert(scene.input_files.begin(), input_files_.begin(), input_files_.end());
  return scene;
}

}  // namespace obj_parse

namespace {

using obj_parse::ObjParser;

// The parser's messages, with the warnings found before an error.
template <typename Parse>
Scene guarded(ObjParser& parser, const std::string& name, Parse parse) {
  try {
    return parse();
  } catch (InputError& e) {
    e.warnings = std::move(parser.warnings());  // found before the error: still shown
    throw;
  } catch (const std::bad_alloc&) {
    throw InputError(name + ": out of memory while loading (input too large)");
  } catch (const std::length_error&) {
    throw InputError(name + ": input too large to load");
  }
}

Scene parse_text(std::string_view text, const std::string& name, const std::string& base_dir,
                 std::size_t max_triangles, StageClock* clock, const ObjChunking& chunking) {
  const int threads = chunking.threads > 0 ? chunking.threads : host_threads();
  const std::size_t chunk_bytes =
      chunking.chunk_bytes > 0 ? chunking.chunk_bytes
                               : std::max<std::size_t>(std::size_t(1) << 20, text.size() / (4 * std::size_t(threads)) + 1);
  const bool chunked = chunking.chunk_bytes > 0 || threads > 1;  // one thread: no chunks unless asked
  if (chunked && text.size() > chunk_bytes && text.size() <= kMaxInputFileBytes) {
    std::vector<ObjParser> chunks;
    if (obj_parse::parse_chunks(text, name, base_dir, max_triangles, clock, chunk_bytes, threads, chunks)) {
      ObjParser whole(text, name, base_dir, max_triangles, clock);
      bool merged = false;
      Scene scene = guarded(whole, name, [&] {
        merged = whole.merge(chunks);
        return merged ? whole.finish() : Scene{};
      });
      if (merged) return scene;
    }
  }
  // One chunk, or a file with an error: read whole, line after line, which
  // names the first error of the file exactly.
  ObjParser parser(text, name, base_dir, max_triangles, clock);
  return guarded(parser, name, [&] { return parser.run(); });
}

}  // namespace

Scene load_obj(const std::string& path, std::size_t max_triangles) {
  const std::string text = read_text_file(path);
  std::string dir = fs::path(path).parent_path().string();
  if (dir.empty()) dir = ".";
  StageClock clock(PrepareStage::parse);
  Scene scene = parse_text(text, path, dir, max_triangles, &clock, ObjChunking{});
  scene.input_files.insert(scene.input_files.begin(), path);
  return scene;
}

Scene load_obj_from_string(const std::string& text, const std::string& name,
                           const std::string& base_dir) {
  return parse_text(text, name, base_dir, kMaxTriangles, nullptr, ObjChunking{});
}

Scene load_obj_from_string(const std::string& text, const std::string& name, const std::string& base_dir,
                           const ObjChunking& chunking, std::size_t max_triangles) {
  return parse_text(text, name, base_dir, max_triangles, nullptr, chunking);
}

}  // namespace opsila
