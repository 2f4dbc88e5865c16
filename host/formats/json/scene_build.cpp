// The triangle budget of a JSON scene's objects (scene_build.h).
#include "formats/json/scene_build.h"

#include <climits>
#include <cmath>

namespace opsila {
namespace scene_json {

void TriangleBudget::add(std::size_t triangles, std::size_t facets, std::size_t objects, const std::string& path,
                         bool windowed) {
  const std::string on_ranks = ranks_ > 1 ? " on " + std::to_string(ranks_) + " ranks (" +
                                                std::to_string(entry_limit_) + " per rank)"
                                          : std::string();
  if (triangles > most_ || planned_triangles_ > most_ - triangles)
    v_.fail(path, "would make " + std::to_string(triangles) + " more triangles (" +
                      std::to_string(planned_triangles_) + " so far); a scene may have at most " +
                      std::to_string(most_) + on_ranks + " (scenes/FORMAT.md, Limits)" +
                      ranks_hint(triangles, windowed));
  if (triangles > entry_limit_ && !(windowed && ranks_ > 1))  // every rank builds an entry whole
    v_.fail(path, "would make " + std::to_string(triangles) + " triangles; one entry of objects may have at most " +
                      std::to_string(entry_limit_) + (windowed ? "" : " on any number of ranks") +
                      " (scenes/FORMAT.md, Limits)");
  if (facets > std::size_t(INT_MAX) - planned_facets_) v_.fail(path, "too many facets for 32-bit ids");
  if (objects > std::size_t(INT_MAX) - planned_objects_) v_.fail(path, "too many objects");
  planned_triangles_ += triangles;
  planned_facets_ += facets;
  planned_objects_ += objects;
}

// How many MPI ranks would take the triangles counted so far, when this
// entry can be spread over them; "" when no number of ranks would (at most
// one per PE, 1024) or the build has no MPI.
std::string TriangleBudget::ranks_hint(std::size_t triangles, bool windowed) const {
#ifdef OPSILA_HAVE_MPI
  const double ranks = std::ceil((double(planned_triangles_) + double(triangles)) / double(entry_limit_));
  if ((triangles > entry_limit_ && !windowed) || ranks > 1024) return "";
  const std::string r = std::to_string(static_cast<int>(ranks));
  return ": with the objects so far it needs at least " + r + " MPI ranks (mpirun -n " + r + " opsila render ...)";
#else
  (void)triangles, (void)windowed;
  return "";
#endif
}

}  // namespace scene_json
}  // namespace opsila
