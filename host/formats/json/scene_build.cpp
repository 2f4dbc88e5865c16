// The triangle budget of a JSON scene's objects (scene_build.h).
#include "formats/json/scene_build.h"

#include <climits>
#include <cmath>

#include "scene/instances.h"

namespace opsila {
namespace scene_json {

void TriangleBudget::add(std::size_t triangles, std::size_t facets, std::size_t objects, const std::string& path,
                         bool windowed) {
  const std::string on_ranks = ranks_ > 1 ? " on " + std::to_string(ranks_) + " ranks (" +
                                                std::to_string(entry_limit_) + " per rank)"
                                          : std::string();
  const std::size_t so_far = planned_triangles_ + everywhere_;
  if (triangles > most_ || so_far > most_ - triangles)
    v_.fail(path, "would make " + std::to_string(triangles) + " more triangles (" + std::to_string(so_far) +
                      " so far); a scene may have at most " + std::to_string(most_) + on_ranks +
                      " (scenes/FORMAT.md, Limits)" + limit_.why_not(so_far + triangles, ranks_) +
                      hint(triangles, windowed));
  if (triangles > entry_limit_ && !(windowed && ranks_ > 1))  // every rank builds an entry whole
    v_.fail(path, "would make " + std::to_string(triangles) + " triangles; one entry of objects may have at most " +
                      std::to_string(entry_limit_) + (windowed ? "" : " on any number of ranks") +
                      " (scenes/FORMAT.md, Limits)" + limit_.why_not(triangles, 1) + hint(triangles, false));
  if (facets > std::size_t(INT_MAX) - planned_facets_) v_.fail(path, "too many facets for 32-bit ids");
  if (objects > std::size_t(INT_MAX) - planned_objects_) v_.fail(path, "too many objects");
  planned_triangles_ += triangles;
  planned_facets_ += facets;
  planned_objects_ += objects;
}

void TriangleBudget::hold_everywhere(std::size_t from, std::size_t placements, const std::string& path) {
  const std::size_t model = planned_triangles_ - from;
  planned_triangles_ = from;
  if (placements > kMaxInstances - instances_)
    v_.fail(path, "more than " + std::to_string(kMaxInstances) + " instances in the scene (scenes/FORMAT.md, Limits)");
  instances_ += placements;
  const std::size_t held = model + kInstanceTriangles * placements;  // placements <= 2^26: no overflow
  add(held, 0, placements, path);
  planned_triangles_ -= held;
  everywhere_ += held;
  if (everywhere_ > entry_limit_)
    v_.fail(path, "the instances' models and placements (" + std::to_string(kInstanceTriangles) +
                      " triangles each) come to " + std::to_string(everywhere_) +
                      " triangles, which every rank holds; at most " + std::to_string(entry_limit_) +
                      " (scenes/FORMAT.md, Limits)" + limit_.why_not(everywhere_, 1));
}

std::string TriangleBudget::beyond(const InputError& e) const {
  return dynamic_cast<const TooManyTriangles*>(&e) ? limit_.why_not(most_, ranks_, true) : std::string();
}

// What would take the triangles counted so far: as many MPI ranks, when
// this entry can be spread over them (at most one per PE, 1024, and only in
// a build with MPI), or as much --host-memory, when memory is what limits.
// An entry every rank builds whole needs the memory on every rank. Past
// kMaxTriangles nothing takes it.
std::string TriangleBudget::hint(std::size_t triangles, bool windowed) const {
  const bool whole = triangles > entry_limit_ && !windowed;
  const std::size_t all = planned_triangles_ + everywhere_ + triangles;
  if (all > kMaxTriangles) return "";  // ids are 32-bit: no ranks or memory take more
  std::string ranks;
#ifdef OPSILA_HAVE_MPI
  const double r = std::ceil(double(all) / double(std::max<std::size_t>(entry_limit_, 1)));
  if (!whole && r <= 1024) {
    const std::string n = std::to_string(static_cast<int>(r));
    ranks = "at least " + n + " MPI ranks (mpirun -n " + n + " opsila render ...)";
  }
#endif
  const std::string memory = whole ? limit_.memory_hint(triangles, 1) : limit_.memory_hint(all, ranks_);
  if (ranks.empty() && memory.empty()) return "";
  return "; with the objects so far it needs " + ranks + (ranks.empty() || memory.empty() ? "" : " or ") + memory;
}

}  // namespace scene_json
}  // namespace opsila
