// The strict OBJ reader's parser, inside host/input: the statements
// (obj_statements.cpp), the scene they make (obj_loader.cpp), and the
// parallel reading of a file in chunks that are merged in file order
// (obj_chunks.cpp).
#pragma once

#include <array>
#include <atomic>
#include <climits>
#include <limits>
#include <memory>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "scene/scene.h"
#include "formats/obj/obj_loader.h"

namespace opsila {

class StageClock;

namespace obj_parse {

struct Polygon {
  std::uint32_t first;  // into the flat index lists
  std::uint32_t count;
  int line;
  int o_seen, g_seen;  // 'o' / 'g' statements before it (its section is the last, 0 when none)
  int slot;            // usemtl slot, -1 = no material (kInherited: the previous chunk's last)
  bool has_uv, has_normals;  // every corner names a vt (vn)
};

constexpr std::uint32_t kNoIndex = 0xffffffffu;
constexpr int kInherited = -2;

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

// The whole file's figures of polygons fanned into triangles (every one, or
// those a window lets go): triangles kept (not zero-area), their bounds,
// degenerate faces and the first face whose edges overflow float.
struct FanFigures {
  std::uint64_t triangles = 0;
  int degenerate = 0, degenerate_line = 0;  // the first one's line (lines grow with ids)
  long long overflow_id = -1;
  int overflow_line = 0;
  Vec3 lo = splat(std::numeric_limits<float>::infinity()), hi = splat(-std::numeric_limits<float>::infinity());
};

// A window's reading (obj_stream.cpp): the polygons kept, in file order,
// and what the polygons let go leave behind.
struct WindowState {
  ModelWindow plan;
  std::size_t examined = 0;               // polys_[0, examined) were examined (and kept)
  std::uint64_t polygons = 0, fans = 0;  // the file's polygons and fan triangles examined
  std::vector<int> id, owner;             // of each kept polygon: its facet id and owner rank
  FanFigures let_go;
  std::vector<char> mapped_slot;          // usemtl slots of let-go faces with uv
  // The ranks holding an object's triangles (lowest, highest), by 'o'
  // section, by 'g' section and for the file as one object: which counts is
  // known at the end.
  std::vector<std::array<int, 2>> by_o, by_g;
  std::array<int, 2> all{{INT_MAX, -1}};
  void note(const Polygon& poly, int owner);
};

// What the parsers of one file's chunks share while they run.
struct ChunkShared {
  std::atomic<bool> stop{false};              // a chunk failed: the file is read again, whole
  std::atomic<std::size_t> triangles{0};      // counted so far, all chunks (the limit)
  std::atomic<std::size_t> bytes{0};          // parsed so far (progress)
  std::size_t total_bytes = 0;
  StageClock* clock = nullptr;
};

// Thrown inside a chunk when another chunk has failed.
struct ChunkStopped {};

class ObjParser {
 public:
  ObjParser(std::string_view text, const std::string& name, const std::string& base_dir,
            std::size_t max_triangles, StageClock* clock)
      : text_(text), name_(name), base_dir_(base_dir), max_triangles_(max_triangles), clock_(clock) {}

  std::vector<std::string>& warnings() { return warnings_; }

  // The whole file, one line after another.
  Scene run();

  // Chunked reading (obj_chunks.cpp). A chunk's parser reads its lines with
  // line numbers counted from its start, and leaves to the merge what needs
  // the chunks before it: negative indices past its start, 'o' / 'g' / usemtl
  // state, and mtllib (read in file order by the merged parser).
  void parse_chunk(bool first, ChunkShared& shared);
  // Appends the chunks, in file order; false when the file has an error no
  // chunk could see alone (the caller then reads it whole, for its message).
  bool merge(std::vector<ObjParser>& chunks);
  Scene finish();

  // Streaming (obj_stream.cpp): the file in blocks, each parsed in chunks
  // and merged (fast; false when a block has an error, the caller then
  // reads again with fast off) or line after line, and the polygons outside
  // the window let go after each block.
  void set_window(const ModelWindow& plan);
  bool stream(const std::string& path, const ObjStreaming& how, bool fast);
  std::uint64_t fans() const { return triangle_total_; }

 private:
  void parse_lines();
  void statement(std::string_view line);
  void vertex(std::string_view rest);
  // Value n (0-based) of a 'v', 'vt' or 'vn' line, or one error naming it.
  float value(std::string_view tok, const char* key, int n);
  void attribute(std::string_view rest, IndexedList& list, const char* key, int min_n, int max_n);
  std::uint32_t index_into(IndexedList& list, long long i, std::string_view tok);
  void vertex_ref(std::string_view tok, std::uint32_t& v, std::uint32_t& vt, std::uint32_t& vn);
  void face(std::string_view rest);
  void usemtl(std::string_view rest);
  void mtllib(std::string_view rest);
  void check_range(IndexedList& list, const std::vector<std::uint32_t>& index, const char* plural);
  void load_maps(Scene& scene, const std::vector<int>& slot_material);
  // finish()'s steps: the scene's materials (returns each slot's), and the
  // faces fanned into triangles (returns the degenerate faces and the line
  // of the first).
  std::vector<int> resolve_materials(Scene& scene);
  FanFigures triangulate(Scene& scene, const std::vector<int>& slot_material);
  bool fan(const Polygon& poly, int id, FanFigures& fig, Scene* out, int object, int material) const;
  void let_go();
  void window_share(Scene& scene, const FanFigures& fig) const;
  std::size_t polygons() const { return (win_ ? win_->polygons - win_->examined : 0) + polys_.size(); }
  int add_attributes(Scene& scene, const Polygon& poly, std::uint32_t k) const;
  void merge_chunk(ObjParser& c, int line_base, int& slot, std::vector<std::pair<int, std::string>>& libs);
  bool resolve_fixups(ObjParser& c, int line_base);

  std::string_view text_;
  const std::string& name_;
  std::string base_dir_;
  std::size_t max_triangles_;
  StageClock* clock_;
  int line_ = 0;
  int line_base_ = 0;  // lines of the blocks before this one (streaming)
  std::unique_ptr<WindowState> win_;

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

  // Chunked reading: the chunk's role, its line count, and what the merge
  // settles (a negative index reaching before the chunk: `rel` counts from
  // the chunk's start; a corner of a short face has no position).
  struct Fixup {
    std::uint32_t pos;  // corner position, or kNoIndex
    int list;           // 0 v, 1 vt, 2 vn
    int poly;           // the chunk's polygon, -1 for a short face
    int line;
    long long rel;
  };
  bool chunk_ = false, first_chunk_ = true;
  ChunkShared* shared_ = nullptr;
  int lines_ = 0;
  std::size_t pending_triangles_ = 0;
  std::vector<Fixup> fixups_;
  std::vector<std::pair<int, std::string>> mtllibs_;

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

// Splits text into chunks of about chunk_bytes that end at line ends (a
// CRLF pair is never split). Together they are the text, in order.
std::vector<std::string_view> split_lines(std::string_view text, std::size_t chunk_bytes);

// Parses each chunk of the text on up to `threads` threads into `chunks`
// (one parser each, in file order). False when a chunk met an error or the
// chunks together pass max_triangles: the caller then reads the text whole.
// file_start: the text is the file's start (else a later block of it).
bool parse_chunks(std::string_view text, const std::string& name, const std::string& base_dir,
                  std::size_t max_triangles, StageClock* clock, std::size_t chunk_bytes, int threads,
                  std::vector<ObjParser>& chunks, bool file_start = true);

}  // namespace obj_parse
}  // namespace opsila
