// An OBJ file read in parallel: split at line ends into chunks, each parsed
// on its own thread with line numbers and indices counted from its start,
// then merged in file order into exactly what one parser reading the lines
// in turn would hold: the same vertices, facets and ids, sections and
// materials, warnings and first line of each. Any error sends the file back
// to that one parser, whose message names the first bad line.
#include <algorithm>
#include <climits>
#include <string>

#include "core/parallel.h"
#include "core/stage_clock.h"
#include "formats/obj/obj_parser.h"
#include "formats/obj/obj_text.h"

namespace opsila {
namespace obj_parse {

std::vector<std::string_view> split_lines(std::string_view text, std::size_t chunk_bytes) {
  std::vector<std::string_view> parts;
  const std::size_t n = text.size(), step = std::max<std::size_t>(1, chunk_bytes);
  for (std::size_t begin = 0; begin < n;) {
    std::size_t end = n;
    if (n - begin > step) {
      // The first line end at or after the nominal end: \n, \r\n or a lone \r,
      // after a line that does not go on in the next (obj_text::LineScanner).
      std::size_t at = text.find_first_of("\r\n", begin + step - 1);
      while (at != std::string_view::npos) {
        const std::size_t after = at + ((text[at] == '\r' && at + 1 < n && text[at + 1] == '\n') ? 2 : 1);
        if (!obj_text::continues_at(text, at)) {
          end = after;
          break;
        }
        at = text.find_first_of("\r\n", after);
      }
    }
    parts.push_back(text.substr(begin, end - begin));
    begin = end;
  }
  return parts;
}

bool parse_chunks(std::string_view text, const std::string& name, const std::string& base_dir,
                  std::size_t max_triangles, StageClock* clock, std::size_t chunk_bytes, int threads,
                  std::vector<ObjParser>& chunks, bool file_start) {
  const std::vector<std::string_view> parts = split_lines(text, chunk_bytes);
  ChunkShared shared;
  shared.total_bytes = text.size();
  shared.clock = clock;
  chunks.reserve(parts.size());
  for (std::string_view part : parts) chunks.emplace_back(part, name, base_dir, max_triangles, nullptr);
  std::vector<char> parsed(parts.size(), 0);
  parallel_for(
      parts.size(),
      [&](std::size_t k) {
        try {
          chunks[k].parse_chunk(k == 0 && file_start, shared);
          parsed[k] = 1;
        } catch (const ChunkStopped&) {
        } catch (...) {  // an error (or no memory): the whole file is read again, for its message
          shared.stop = true;
        }
      },
      threads);
  if (std::find(parsed.begin(), parsed.end(), 0) == parsed.end()) return true;
  std::vector<ObjParser>().swap(chunks);
  return false;
}

void ObjParser::parse_chunk(bool first, ChunkShared& shared) {
  chunk_ = true;
  first_chunk_ = first;
  shared_ = &shared;
  slot_ = kInherited;
  parse_lines();
  if ((shared.triangles += pending_triangles_) > max_triangles_) shared.stop = true;
  pending_triangles_ = 0;
}

// Negative indices that reach before chunk c, now that the lists before it
// are known: an index, or (past the file's start) an error or a corner
// without that attribute, as the one parser would have decided.
bool ObjParser::resolve_fixups(ObjParser& c, int line_base) {
  IndexedList* lists[3] = {&verts_, &uvs_, &normals_};
  std::vector<std::uint32_t>* index[3] = {&c.index_, &c.uv_index_, &c.normal_index_};
  for (const Fixup& f : c.fixups_) {
    IndexedList& list = *lists[f.list];
    const long long i = list.size() + f.rel;
    if (i >= 0) {
      if (f.pos != kNoIndex) (*index[f.list])[f.pos] = static_cast<std::uint32_t>(i);
      continue;
    }
    if (list.strict) return false;
    if (list.missing++ == 0) list.missing_line = line_base + f.line;
    if (f.pos == kNoIndex) continue;
    (*index[f.list])[f.pos] = kNoIndex;
    Polygon& poly = c.polys_[static_cast<std::size_t>(f.poly)];
    (f.list == 1 ? poly.has_uv : poly.has_normals) = false;
  }
  std::vector<Fixup>().swap(c.fixups_);
  return true;
}

template <typename T>
void append_and_free(std::vector<T>& to, std::vector<T>& from) {
  to.insert(to.end(), from.begin(), from.end());
  std::vector<T>().swap(from);
}

// Chunk c after the chunks before it: `slot` is the material slot in use
// where it starts; `libs` collects its mtllib lines.
void ObjParser::merge_chunk(ObjParser& c, int line_base, int& slot, std::vector<std::pair<int, std::string>>& libs) {
  std::vector<int> to_slot(c.slot_names_.size());
  for (std::size_t s = 0; s < c.slot_names_.size(); ++s) {
    auto it = slot_of_.find(c.slot_names_[s]);
    if (it == slot_of_.end()) {
      it = slot_of_.emplace(c.slot_names_[s], static_cast<int>(slot_names_.size())).first;
      slot_names_.push_back(c.slot_names_[s]);
      slot_lines_.push_back(line_base + c.slot_lines_[s]);
    }
    to_slot[s] = it->second;
  }
  const auto corner_base = static_cast<std::uint32_t>(index_.size());
  for (Polygon& p : c.polys_) {
    p.first += corner_base;
    p.line += line_base;
    p.o_seen += o_count_;
    p.g_seen += g_count_;
    p.slot = p.slot == kInherited ? slot : to_slot[static_cast<std::size_t>(p.slot)];
  }
  if (c.slot_ != kInherited) slot = to_slot[static_cast<std::size_t>(c.slot_)];
  IndexedList* mine[3] = {&verts_, &uvs_, &normals_};
  IndexedList* theirs[3] = {&c.verts_, &c.uvs_, &c.normals_};
  for (int k = 0; k < 3; ++k) {
    IndexedList &to = *mine[k], &from = *theirs[k];
    if (from.max_index > to.max_index) to.max_index = from.max_index, to.max_line = line_base + from.max_line;
    append_and_free(to.values, from.values);
  }
  append_and_free(index_, c.index_);
  append_and_free(uv_index_, c.uv_index_);
  append_and_free(normal_index_, c.normal_index_);
  append_and_free(polys_, c.polys_);
  triangle_total_ += c.triangle_total_;
  o_count_ += c.o_count_;
  g_count_ += c.g_count_;
  if (c.short_faces_ > 0 && short_faces_ == 0) short_line_ = line_base + c.short_line_;
  short_faces_ += c.short_faces_;
  if (c.unknown_count_ > 0 && unknown_count_ == 0) {
    unknown_line_ = line_base + c.unknown_line_;
    unknown_first_ = c.unknown_first_;
  }
  unknown_count_ += c.unknown_count_;
  for (auto& [line, rest] : c.mtllibs_) libs.emplace_back(line_base + line, std::move(rest));
}

bool ObjParser::merge(std::vector<ObjParser>& chunks) {
  // A streamed file's blocks merge in turn: what this parser holds comes first.
  std::size_t corners = index_.size(), polys = polygons(), kept = polys_.size();
  for (const ObjParser& c : chunks) corners += c.index_.size(), polys += c.polys_.size(), kept += c.polys_.size();
  if (polys > static_cast<std::size_t>(INT_MAX) || corners >= kNoIndex) return false;
  index_.reserve(corners);
  uv_index_.reserve(corners);
  normal_index_.reserve(corners);
  polys_.reserve(kept);
  int line_base = line_base_, slot = slot_;
  std::vector<std::pair<int, std::string>> libs;
  for (ObjParser& c : chunks) {
    // The first chunk's own missing attributes come first in the file.
    IndexedList* mine[2] = {&uvs_, &normals_};
    const IndexedList* theirs[2] = {&c.uvs_, &c.normals_};
    for (int k = 0; k < 2; ++k) {
      if (theirs[k]->missing == 0) continue;
      if (mine[k]->missing == 0) mine[k]->missing_line = line_base + theirs[k]->missing_line;
      mine[k]->missing += theirs[k]->missing;
    }
    if (!resolve_fixups(c, line_base)) return false;
    merge_chunk(c, line_base, slot, libs);
    line_base += c.lines_;
  }
  std::vector<ObjParser>().swap(chunks);
  line_base_ = line_base;
  slot_ = slot;
  if (triangle_total_ > max_triangles_) return false;
  // Material libraries last: reading them changes nothing above, and their
  // warnings come in file order before any later one.
  for (auto& [line, rest] : libs) {
    line_ = line;
    mtllib(rest);
  }
  return true;
}

}  // namespace obj_parse
}  // namespace opsila
