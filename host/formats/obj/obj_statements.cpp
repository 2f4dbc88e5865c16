// The OBJ statements, line by line (obj_parser.h): vertices, attributes,
// faces and their indices, object and group sections, materials.
#include <climits>
#include <filesystem>
#include <string>
#include <system_error>

#include "core/stage_clock.h"
#include "formats/obj/obj_loader.h"
#include "formats/obj/obj_parser.h"
#include "formats/obj/obj_text.h"
#include "formats/image/texture_file.h"
#include "opsila_shared.h"

namespace opsila {
namespace obj_parse {

namespace fs = std::filesystem;
using namespace obj_text;

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

}  // namespace

Scene ObjParser::run() {
  if (text_.size() > kMaxInputFileBytes)
    throw InputError(name_ + ": input too large (" + std::to_string(text_.size()) + " bytes)");
  parse_lines();
  return finish();
}

void ObjParser::parse_lines() {
  // A chunk other than the first starts mid-file: no byte-order mark there.
  LineScanner sc(text_, name_, chunk_ ? first_chunk_ : line_base_ == 0);
  std::string_view line;
  std::size_t reported = 0;
  while (sc.next(line)) {
    line_ = line_base_ + sc.line_no();
    if ((sc.lines() & 0xffff) == 0) {
      const std::size_t at = static_cast<std::size_t>(line.data() - text_.data());
      if (shared_) {
        if (shared_->stop.load(std::memory_order_relaxed)) throw ChunkStopped{};
        const std::size_t all = shared_->bytes += at - reported;
        if (shared_->clock) shared_->clock->progress(double(all) / double(shared_->total_bytes));
      } else if (clock_) {
        clock_->progress(double(at) / double(text_.size()));
      }
      reported = at;
    }
    statement(line);
  }
  lines_ = sc.lines();
}

void ObjParser::statement(std::string_view line) {
  std::string_view rest = line;
  const std::string_view kw = next_token(rest);
  if (kw.empty() || kw[0] == '#') return;
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
    return;
  } else if (is_identifier(kw)) {
    if (unknown_count_++ == 0) {
      unknown_line_ = line_;
      unknown_first_ = std::string(kw);
    }
  } else {
    fail(name_, line_, "invalid statement " + quote(kw) + " (binary file or not OBJ?)");
  }
}

float ObjParser::value(std::string_view tok, const char* key, int n) {
  float x;
  const Num s = parse_float(tok, x);
  if (s != Num::ok)
    fail(name_, line_, std::string("'") + key + "' value " + std::to_string(n + 1) + " " + quote(tok) + " " +
                           describe(s));
  return x;
}

void ObjParser::vertex(std::string_view rest) {
  float xyz[3] = {0, 0, 0};
  int n = 0;
  for (std::string_view tok = next_token(rest); !tok.empty(); tok = next_token(rest)) {
    if (tok[0] == '#') break;
    const float x = value(tok, "v", n);
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
void ObjParser::attribute(std::string_view rest, IndexedList& list, const char* key, int min_n, int max_n) {
  float xyz[3] = {0, 0, 0};
  int n = 0;
  for (std::string_view tok = next_token(rest); !tok.empty(); tok = next_token(rest)) {
    if (tok[0] == '#') break;
    const float x = value(tok, key, n);
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
std::uint32_t ObjParser::index_into(IndexedList& list, long long i, std::string_view tok) {
  if (i == 0)
    fail(name_, line_, std::string(list.what) + " index 0 in " + quote(tok) + " (OBJ indices start at 1)");
  const long long have = list.size();
  if (i < 0 && chunk_ && !first_chunk_) {
    // Counted from the chunk's start: the merge adds what the chunks before
    // define (and decides whether it names anything).
    const int id = &list == &verts_ ? 0 : &list == &uvs_ ? 1 : 2;
    fixups_.push_back(Fixup{static_cast<std::uint32_t>(index_.size()), id, static_cast<int>(polys_.size()), line_,
                            have + i});
    return 0;
  }
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
void ObjParser::vertex_ref(std::string_view tok, std::uint32_t& v, std::uint32_t& vt, std::uint32_t& vn) {
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


void ObjParser::face(std::string_view rest) {
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
    for (auto f = fixups_.rbegin(); f != fixups_.rend() && f->poly == static_cast<int>(polys_.size()); ++f)
      f->pos = kNoIndex, f->poly = -1;  // still checked, for the error or the warning
    if (short_faces_++ == 0) short_line_ = line_;
    return;
  }
  if (n - 2 > OPSILA_MAX_FAN)
    check_fan_triangles(static_cast<long long>(n) - 2, at(name_, line_) + "'f' line of " + std::to_string(n) + " corners: ");
  if (polygons() >= static_cast<std::size_t>(INT_MAX))
    fail(name_, line_, "too many facets (more than " + std::to_string(INT_MAX) + ")");
  triangle_total_ += n - 2;
  if (triangle_total_ > max_triangles_)
    throw TooManyTriangles(at(name_, line_) + "too many triangles (more than " + std::to_string(max_triangles_) +
                           ", scenes/FORMAT.md, Limits)");
  if (shared_ && (pending_triangles_ += n - 2) >= 4096) {
    // All chunks together past the limit: stop early (the whole file is then
    // read again, to fail on the right line).
    if ((shared_->triangles += pending_triangles_) > max_triangles_) {
      shared_->stop = true;
      throw ChunkStopped{};
    }
    pending_triangles_ = 0;
  }
  polys_.push_back(Polygon{static_cast<std::uint32_t>(start), n, line_, o_count_, g_count_, slot_, all_uv,
                           all_normals});
}


void ObjParser::usemtl(std::string_view rest) {
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


void ObjParser::mtllib(std::string_view rest) {
  if (chunk_) {  // read by the merged parser, in file order
    mtllibs_.emplace_back(line_, std::string(rest));
    return;
  }
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
      // A folder, a device or a pipe is there but is no file to read.
      const bool there = fs::exists(path, ec);
      warnings_.push_back(at(name_, line_) + "material library " + quote(f) +
                          (there ? (fs::is_directory(path, ec) ? " is a folder, not a file ("
                                                               : " is not a regular file (")
                                 : " not found (") +
                          quote(path) + "); faces using its materials get the default material");
      continue;
    }
    if (fs::equivalent(path, name_, ec)) {  // an OBJ read as its own materials, without a word
      warnings_.push_back(at(name_, line_) + "material library " + quote(f) +
                          " is this OBJ file itself (ignored); faces using its materials get the default material");
      continue;
    }
    std::string text;
    try {
      text = read_text_file(path);
    } catch (const InputError& e) {  // there, but unreadable or too large: named from the line that asks for it
      throw InputError(at(name_, line_) + "mtllib " + quote(f) + ": " + e.what());
    }
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

}  // namespace obj_parse
}  // namespace opsila
