// A rank's window of a model file read as a stream: which of the file's
// polygons this rank keeps. One rule for every streamed format.
#pragma once

#include <cstdint>

#include "scene/scene.h"

namespace opsila {

// One rank's window of a model read as a stream (OBJ, PLY, STL; docs/DISTRIBUTED.md): the
// file's fan triangles take [plan_begin, plan_begin + plan_all) of a plan
// of plan_total triangles dealt over `ranks` in equal slices, and this rank
// keeps the polygons whose first fan triangle falls in its slice (a polygon
// is never cut). fans: the file's fan triangles, counted by a first read; 0
// keeps no polygon (that first read: counts, materials, warnings, errors).
struct ModelWindow {
  int rank = 0, ranks = 1;
  std::uint64_t plan_begin = 0, plan_all = 0, plan_total = 0;
  std::uint64_t fans = 0;
  bool load_maps = true;  // the materials' texture maps (the read that keeps the materials)
  MapImages map_images = MapImages::now;  // and how their images are read (add_texture_file)
};
// The rank whose slice of the plan holds the file's fan triangle `fan`
// (-1 when the window keeps nothing: the counting read). The PLY stream's
// rule too.
int window_owner(const ModelWindow& plan, std::uint64_t fan);

}  // namespace opsila
