#include "frame/frame.h"

#include <algorithm>

namespace opsila {

// The hit list of the sample pass the item buffer holds (kernels/primary.cl):
// its misses are done here, and the list's length comes back to the host,
// which injects that many primary descriptors. With several ranks, every
// rank lists the same pixels (the item buffer is relayed whole), so they
// decide alike. The frame's first pass (sample 0) writes every pixel's
// sums, which are not cleared before the frame (frame_buffers.cpp).
std::size_t Renderer::Machine::list_hits(Launcher& launch, int sample) {
  const int pixels = static_cast<int>(npix);
  const int blocks = (pixels + ScatterPass::kBlock - 1) / ScatterPass::kBlock;
  kernels().count_hits.bind(fp, b_item_tri, pixels, traced_rect, sample == 0 ? 1 : 0, b_hit_blocks, b_accum);
  launch.run(kernels().count_hits.kernel(), "count_hits", round_up(blocks, 64), 0, -1);
  scatter->scan(launch, "hit_list_scan", b_hit_blocks, blocks, b_hit_total, -1);
  kernels().list_hits.bind(b_item_tri, pixels, width, traced_rect, b_hit_blocks, b_hit_pixels);
  launch.run(kernels().list_hits.kernel(), "list_hits", round_up(blocks, 64), 0, -1);
  cl_int listed = 0;
  launch.check(rt.queue().enqueueReadBuffer(b_hit_total, CL_TRUE, 0, sizeof(cl_int), &listed),
               "clEnqueueReadBuffer(hit list length)");
  return static_cast<std::size_t>(listed);
}

// Primary descriptors (SIMD), built from the hit list into the waiting pool
// when it runs short, bound for the PEs that own the items. When a sample
// pass is used up, the next sample's item buffer pass and hit list come
// first (the in-order queue runs them after the builds that read the
// previous ones), so the descriptors in flight stay bounded by the
// injection whatever N is.
void Renderer::Machine::primary_descriptors(Launcher& launch, Frame& f, int round) {
  // Several ranks decide alike (on the longest pool of any): each builds the
  // descriptors of its own PEs from the same pixels, and the item buffer
  // passes, relayed between ranks, start on every rank in the same round.
  if ((group.all() ? f.pool_len : f.pool_len_max) >= flight.inject) return;
  while (f.next_hit >= f.listed && f.sample + 1 < spp) {
    item_buffer(launch, ++f.sample);
    f.listed = list_hits(launch, f.sample);
    f.next_hit = 0;
  }
  if (f.next_hit >= f.listed) return;
  std::size_t count = std::min(flight.inject, f.listed - f.next_hit);
  if (!group.all() && f.pool_len + count > pool.capacity) {
    DescriptorSet bigger;
    bigger.allocate(rt, (f.pool_len + count) * 3 / 2, "descriptor pool");
    pool.copy_prefix_to(rt, bigger, f.pool_len);
    pool = bigger;
  }
  if (f.pool_len + count > pool.capacity) count = pool.capacity - f.pool_len;
  kernels().primary.bind(fp, b_pes, b_hit_pixels, b_item_tri, b_item_t, static_cast<int>(f.next_hit),
                         static_cast<int>(count), offsets[std::size_t(f.sample % spp_k)],
                         offsets[std::size_t(f.sample / spp_k)], static_cast<int>(f.pool_len), pool, b_hits);
  launch.run(kernels().primary.kernel(), "build_primary", round_up(count, 64), 0, round);
  f.next_hit += count;
  f.pool_len += count;
}

}  // namespace opsila
