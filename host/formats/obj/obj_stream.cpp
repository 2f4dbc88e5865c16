// An OBJ read as a stream by one MPI rank (docs/DISTRIBUTED.md): the file
// in blocks cut at line ends, each parsed as obj_chunks.cpp parses a whole
// file (chunks on the host threads, merged in file order) into one parser
// that keeps every v, vt and vn but, after each block, lets go of the
// polygons outside the rank's window. A polygon let go is fanned at once
// (its vertices are all defined, and never change), so the file's triangle
// count, bounds, degenerate faces, textured materials and the ranks its
// objects fall on are known to every rank alike, with no message. The text
// of a block is freed before the next is read.
#include <algorithm>
#include <filesystem>
#include <new>
#include <stdexcept>
#include <string>

#include "core/parallel.h"
#include "core/stage_clock.h"
#include "formats/obj/obj_text.h"
#include "formats/obj/obj_parser.h"

namespace opsila {
namespace obj_parse {

namespace {

// Calls `block` with the file's text in pieces of about block_bytes that
// end at line ends (a CRLF pair is never split), checked as read_text_file
// checks a file.
void stream_blocks(const std::string& path, std::size_t block_bytes,
                   const std::function<void(std::string_view, double)>& block) {
  std::string buf;
  std::uintmax_t size = 0, done = 0;
  const auto cut = [&](bool at_end) {
    std::size_t end = buf.size();
    if (!at_end) {
      // After the last \n, or else the last lone \r that is not the last
      // byte, that ends a line not going on in the next.
      const std::string_view text(buf);
      std::size_t nl = text.rfind('\n');
      while (nl != std::string::npos && obj_text::continues_at(text, nl))
        nl = nl == 0 ? std::string::npos : text.rfind('\n', nl - 1);
      std::size_t cr = text.size() >= 2 ? text.rfind('\r', text.size() - 2) : std::string::npos;
      while (cr != std::string::npos && (text[cr + 1] == '\n' || obj_text::continues_at(text, cr)))
        cr = cr == 0 ? std::string::npos : text.rfind('\r', cr - 1);
      if (nl != std::string::npos) end = nl + 1;
      else if (cr != std::string::npos) end = cr + 1;
      else return;  // one long line so far: read on
    }
    done += end;
    block(std::string_view(buf.data(), end), size > 0 ? double(done) / double(size) : 1.0);
    buf.erase(0, end);
  };
  read_file_chunks(path, kMaxInputFileBytes, text_check(path), [&](std::uintmax_t s) { size = s; },
                   [&](const char* data, std::size_t n) {
                     buf.append(data, n);
                     if (buf.size() >= block_bytes) cut(false);
                   });
  if (!buf.empty()) cut(true);
}

}  // namespace

void WindowState::note(const Polygon& poly, int owner) {
  if (owner < 0) return;
  const auto widen = [owner](std::array<int, 2>& span) {
    span[0] = std::min(span[0], owner);
    span[1] = std::max(span[1], owner);
  };
  for (auto [list, seen] : {std::pair{&by_o, poly.o_seen}, std::pair{&by_g, poly.g_seen}}) {
    const std::size_t object = std::size_t(std::max(0, seen - 1));
    if (list->size() <= object) list->resize(object + 1, {{INT_MAX, -1}});
    widen((*list)[object]);
  }
  widen(all);
}

void ObjParser::set_window(const ModelWindow& plan) {
  win_ = std::make_unique<WindowState>();
  win_->plan = plan;
}

// The polygons read since the last call: this rank's are kept, and so are
// those that name an index not defined yet (decided at the end); the others
// are fanned into the figures now and let go, with their corners.
void ObjParser::let_go() {
  WindowState& w = *win_;
  std::size_t keep = w.examined;
  std::uint32_t corner = keep == 0 ? 0 : polys_[keep - 1].first + polys_[keep - 1].count;
  const auto defined = [&](const std::vector<std::uint32_t>& index, const IndexedList& list, const Polygon& p) {
    for (std::uint32_t k = p.first; k < p.first + p.count; ++k)
      if (index[k] != kNoIndex && index[k] >= list.size()) return false;
    return true;
  };
  for (std::size_t f = w.examined; f < polys_.size(); ++f) {
    Polygon p = polys_[f];
    const int id = static_cast<int>(w.polygons++);
    const int owner = window_owner(w.plan, w.fans);
    w.fans += p.count - 2;
    const bool mine = owner >= 0 && owner == w.plan.rank;
    if (!mine && defined(index_, verts_, p) && defined(uv_index_, uvs_, p) && defined(normal_index_, normals_, p)) {
      if (fan(p, id, w.let_go, nullptr, 0, 0)) w.note(p, owner);
      if (p.has_uv && p.slot >= 0) {
        if (w.mapped_slot.size() <= std::size_t(p.slot)) w.mapped_slot.resize(std::size_t(p.slot) + 1, 0);
        w.mapped_slot[std::size_t(p.slot)] = 1;
      }
      continue;
    }
    for (std::vector<std::uint32_t>* index : {&index_, &uv_index_, &normal_index_})
      std::copy(index->begin() + p.first, index->begin() + p.first + p.count, index->begin() + corner);
    p.first = corner;
    corner += p.count;
    polys_[keep++] = p;
    w.id.push_back(id);
    w.owner.push_back(owner);
  }
  polys_.resize(keep);
  for (std::vector<std::uint32_t>* index : {&index_, &uv_index_, &normal_index_}) index->resize(corner);
  w.examined = keep;
}

// The window's figures for the scene: the whole file's triangle count and
// bounds, and its objects whose triangles lie on several ranks, in id order.
void ObjParser::window_share(Scene& scene, const FanFigures& fig) const {
  scene.share.rank = win_->plan.rank;
  scene.share.ranks = win_->plan.ranks;
  scene.share.total_triangles = fig.triangles;
  scene.share.lo = fig.lo;
  scene.share.hi = fig.hi;
  const std::vector<std::array<int, 2>>& spans = o_count_ > 0 ? win_->by_o : win_->by_g;
  if (o_count_ == 0 && g_count_ == 0) {
    if (win_->all[0] < win_->all[1]) scene.share.spread.push_back(0);
    return;
  }
  for (std::size_t o = 0; o < spans.size(); ++o)
    if (spans[o][0] < spans[o][1]) scene.share.spread.push_back(static_cast<int>(o));
}

bool ObjParser::stream(const std::string& path, const ObjStreaming& how, bool fast) {
  const int threads = how.chunking.threads > 0 ? how.chunking.threads : host_threads();
  const std::size_t block_bytes = std::max<std::size_t>(how.block_bytes, 1);
  const std::size_t chunk_bytes = how.chunking.chunk_bytes > 0
                                      ? how.chunking.chunk_bytes
                                      : std::max<std::size_t>(std::size_t(1) << 20, block_bytes / (4 * std::size_t(threads)) + 1);
  StageClock clock(PrepareStage::parse);
  bool ok = true;
  stream_blocks(path, block_bytes, [&](std::string_view block, double done) {
    if (!ok) return;
    if (fast) {
      std::vector<ObjParser> chunks;
      ok = parse_chunks(block, name_, base_dir_, max_triangles_, nullptr, chunk_bytes, threads, chunks,
                        line_base_ == 0) &&
           merge(chunks);
    } else {  // line after line, as one process reads a file with an error
      text_ = block;
      parse_lines();
      line_base_ += lines_;
      text_ = std::string_view();
    }
    if (ok) let_go();
    clock.progress(done);
  });
  return ok;
}

}  // namespace obj_parse

Scene load_obj_window(const std::string& path, std::size_t max_triangles, const ModelWindow& window,
                      std::uint64_t& fans, const ObjStreaming& streaming) {
  using obj_parse::ObjParser;
  std::string dir = std::filesystem::path(path).parent_path().string();
  if (dir.empty()) dir = ".";
  std::unique_ptr<ObjParser> parser;
  const auto read = [&](bool fast) {
    parser = std::make_unique<ObjParser>(std::string_view(), path, dir, max_triangles, nullptr);
    parser->set_window(window);
    return parser->stream(path, streaming, fast);
  };
  try {
    if (!read(true)) {
      // An error: read again line after line for its message, then the rest
      // of the file for a binary byte, which one process meets first.
      try {
        read(false);
      } catch (const InputError&) {
        read_file_chunks(path, kMaxInputFileBytes, text_check(path), [](std::uintmax_t) {},
                         [](const char*, std::size_t) {});
        throw;
      }
    }
    Scene scene = parser->finish();
    fans = parser->fans();
    scene.input_files.insert(scene.input_files.begin(), path);
    return scene;
  } catch (InputError& e) {
    if (parser) e.warnings = std::move(parser->warnings());  // found before the error: still shown
    throw;
  } catch (const std::bad_alloc&) {
    throw InputError(path + ": out of memory while loading (input too large)");
  } catch (const std::length_error&) {
    throw InputError(path + ": input too large to load");
  }
}

}  // namespace opsila
