// A rank's share of a JSON scene (docs/DISTRIBUTED.md): which of each
// entry's triangles this rank keeps, and the whole scene's figures counted
// as the entries are built. Every input is explicit: the entry, its part
// of the plan and the plan's size. Internal to formats/json.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "formats/common/window.h"
#include "scene/scene.h"

namespace opsila {
namespace scene_json {

// An entry of "objects" as the dealing sees it: its part of the plan of
// the scene's triangles, its exact size when known before it is built (a
// generator's), how many of its triangles were dealt so far, and whether
// each rank made only its window of it.
struct EntryShare {
  std::size_t planned_begin = 0, planned_end = 0;
  std::size_t expected = 0;
  std::size_t dealt = 0;
  bool windowed = false;
};

class ShareDealer {
 public:
  explicit ShareDealer(const SceneShare& share) : share_(share) {}

  // Several ranks: the scene is read as this rank's share (not while a
  // Whole is held).
  bool active() const { return share_.ranks > 1 && !whole_; }
  // While one is held, entries are planned and built whole, as on one rank:
  // an instances entry's model, which every rank keeps.
  class Whole {
   public:
    explicit Whole(ShareDealer& dealer) : dealer_(dealer), was_(dealer.whole_) { dealer.whole_ = true; }
    ~Whole() { dealer_.whole_ = was_; }
    Whole(const Whole&) = delete;
    Whole& operator=(const Whole&) = delete;

   private:
    ShareDealer& dealer_;
    bool was_;
  };
  const SceneShare& share() const { return share_; }

  // The entry's triangles from `first` (its attributes from
  // first_attribute), counted into the figures; only the objects dealt to
  // this rank stay. `planned`: the plan's triangles.
  void deal(Scene& scene, EntryShare& entry, std::size_t first, std::size_t first_attribute, std::size_t planned);
  // A windowed entry of `all` triangles: [begin, end) of them are this
  // rank's to make; `object` is spread when the window cuts it.
  void window(EntryShare& entry, std::size_t all, int object, std::size_t planned, std::size_t& begin,
              std::size_t& end);
  // The window of a model file read again as a stream, for an entry of the
  // file's `fans` fan triangles.
  ModelWindow file_window(EntryShare& entry, std::size_t planned, std::uint64_t fans);
  // A windowed entry's triangles from `first`, all this rank's: counted.
  void count_window(const Scene& scene, std::size_t first);
  // What this rank read of a file it streamed (FileReadStamp::after).
  void add_read(const std::string& file, std::vector<std::uint64_t> stamp);
  // An object whose triangles lie on several ranks.
  void add_spread(int object) { share_.spread.push_back(object); }
  // A windowed entry's zero-area triangles dropped here (warned about
  // once summed over the ranks, by finish).
  void add_window_dropped(const std::string& path, std::size_t dropped);

  // The scene's instances, which every rank keeps, into this rank's bounds.
  void add_instances(const Scene& scene);

  // After every entry: the figures joined over the ranks (share.combine),
  // the windowed entries' dropped triangles said by `warn_dropped`, the
  // share into the scene.
  void finish(Scene& scene, const std::function<void(const std::string&, std::size_t)>& warn_dropped);

 private:
  void grow_bounds(const Triangle& t);
  void grow_bounds(const Vec3& p);

  SceneShare share_;           // rank and ranks; the whole scene's figures as they are built
  std::vector<int> owner_;     // object id -> the rank it is dealt to (-1: not yet seen)
  bool bounded_ = false;       // share_.lo/hi hold a triangle or an instance
  bool whole_ = false;         // a Whole is held
  std::vector<std::string> window_paths_;  // the windowed entries, as share_.window_dropped
};

}  // namespace scene_json
}  // namespace opsila
