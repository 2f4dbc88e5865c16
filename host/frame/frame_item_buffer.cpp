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
               std::size_t(tile_w) * tile_w, -1, nullptr, Launcher::Watch::always);
    if (!group.all()) relay.send(px0, px1 - px0);
  }
  if (!group.all()) relay.share(npix);
}

}  // namespace opsila

namespace opsila {

namespace {

// A rectangle's bins (inclusive), clamped to the screen; false when it
// lies outside it (kNeverListed among them).
bool bin_span(const cl_int4& r, int width, int height, int side, int (&b)[4]) {
  const int x0 = std::max(r.s[0], 0), y0 = std::max(r.s[1], 0);
  const int x1 = std::min(r.s[2], width - 1), y1 = std::min(r.s[3], height - 1);
  if (x0 > x1 || y0 > y1) return false;
  b[0] = x0 / side, b[1] = y0 / side, b[2] = x1 / side, b[3] = y1 / side;
  return true;
}

}  // namespace

ItemBins item_bins(const std::vector<cl_int4>& rects, int width, int height, int tile_w) {
  ItemBins bins;
  bins.side = tile_w;
  const int most = std::max(width, height);
  for (;;) {  // the finest bins whose lists fit
    std::size_t entries = 0;
    int b[4];
    for (const cl_int4& r : rects)
      if (bin_span(r, width, height, bins.side, b)) entries += std::size_t(b[2] - b[0] + 1) * (b[3] - b[1] + 1);
    if (entries <= kMaxItemBinEntries || bins.side >= most) break;
    bins.side *= 2;
  }
  bins.bins_x = (width + bins.side - 1) / bins.side;
  const int bins_y = (height + bins.side - 1) / bins.side;
  std::vector<int> count(std::size_t(bins.bins_x) * bins_y + 1, 0);
  int b[4];
  for (const cl_int4& r : rects)
    if (bin_span(r, width, height, bins.side, b))
      for (int y = b[1]; y <= b[3]; ++y)
        for (int x = b[0]; x <= b[2]; ++x) ++count[std::size_t(y) * bins.bins_x + x];
  bins.first.assign(count.size(), 0);
  for (std::size_t k = 1; k < count.size(); ++k) bins.first[k] = bins.first[k - 1] + count[k - 1];
  bins.list.assign(std::max<std::size_t>(1, std::size_t(bins.first.back())), -1);
  std::vector<int> at(bins.first.begin(), bins.first.end() - 1);
  for (std::size_t c = 0; c < rects.size(); ++c)
    if (bin_span(rects[c], width, height, bins.side, b))
      for (int y = b[1]; y <= b[3]; ++y)
        for (int x = b[0]; x <= b[2]; ++x) bins.list[std::size_t(at[std::size_t(y) * bins.bins_x + x]++)] = int(c);
  return bins;
}

}  // namespace opsila
