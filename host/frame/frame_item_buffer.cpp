#include "frame/frame.h"

#include <algorithm>

namespace opsila {

// SIMD phase 1, the item buffer: one work-group per square tile of pixels,
// over the tiles that overlap traced_rect (frame.h: the whole image, or on
// one device without item buffer output only where a cluster's rectangle
// lies, none at all when the view meets no cluster); launches are bounded
// to about `item_buffer_tile` pixels each so that no launch runs unbounded.
//
// One pass per sample (0 .. N-1, i rightwards, j downwards) keeps the
// nearest hits for that sample's primary descriptors; the (object, facet)
// output is the centre ray's: the centre sample's pass writes it for odd k,
// a pass of its own (sample -1, no hits kept) for even k; neither when the
// frame gives no item buffer (RenderSettings::item_buffer_output). With several
// ranks, each launch covers whole rows of tiles, which the ranks relay in
// turn (rank_exchange.h), and every pass keeps its hits (the relayed state).
void Renderer::Machine::item_buffer(Launcher& launch, int sample) {
  const bool centre_only = sample < 0;
  const int i = centre_only ? 0 : sample % spp_k, j = centre_only ? 0 : sample / spp_k;
  const bool centre = centre_only || (2 * i + 1 == spp_k && 2 * j + 1 == spp_k);
  const bool items = centre && item_output;
  const int mode = (items ? OPSILA_ITEM_WRITE_ITEMS : 0) |
                   (centre_only && group.all() ? 0 : OPSILA_ITEM_WRITE_HITS);
  const float ox = centre_only ? 0.5f : offsets[std::size_t(i)], oy = centre_only ? 0.5f : offsets[std::size_t(j)];
  const bool none = traced_rect.s[0] > traced_rect.s[2] || traced_rect.s[1] > traced_rect.s[3];
  const cl_int2 origin{{none ? 0 : traced_rect.s[0] / tile_w, none ? 0 : traced_rect.s[1] / tile_w}};
  const int tiles_x = none ? 0 : traced_rect.s[2] / tile_w - origin.s[0] + 1;
  const int tiles_y = none ? 0 : traced_rect.s[3] / tile_w - origin.s[1] + 1;
  const int tiles = tiles_x * tiles_y;
  int per_launch = std::max(1, item_launch_pixels / (tile_w * tile_w));
  if (!group.all()) per_launch = std::max(1, per_launch / tiles_x) * tiles_x;
  ItemRelay relay(ranks, rt, ItemBuffers{&item.items.buffer, &item.tri.buffer, &item.t.buffer, &item.key.buffer, items});
  frame_kernels::ItemBufferArgs a;
  a.fp = fp;
  a.clusters = item_list;
  a.geometry = geometry;
  a.tile_w = tile_w;
  a.tile_origin = origin;
  a.tiles_x = tiles_x;
  a.ox = ox;
  a.oy = oy;
  a.mode = mode;
  a.item = item;
  for (int begin = 0; begin < tiles; begin += per_launch) {
    const int count = std::min(per_launch, tiles - begin);
    const std::size_t px0 = std::size_t(origin.s[1] + begin / tiles_x) * tile_w * width;
    const std::size_t px1 = std::min(npix, std::size_t(origin.s[1] + (begin + count) / tiles_x) * tile_w * width);
    if (!group.all()) relay.receive(px0, px1 - px0);
    a.tile_begin = begin;
    kernels().item.bind(a);
    launch.run(kernels().item.kernel(), "item_buffer", std::size_t(count) * tile_w * tile_w,
               std::size_t(tile_w) * tile_w, -1);
    if (!group.all()) relay.send(px0, px1 - px0);
  }
  if (!group.all()) relay.share(npix);
}

}  // namespace opsila
