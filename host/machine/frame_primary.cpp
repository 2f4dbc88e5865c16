#include "machine/frame.h"

#include <algorithm>

namespace opsila {

// Primary descriptors (SIMD), built from the item buffer into the waiting
// pool when it runs short, bound for the PEs that own the items. When a
// sample pass is used up, the next sample's item buffer pass runs first (the
// in-order queue runs it after the builds that read the previous one), so
// the descriptors in flight stay bounded by the injection whatever N is.
void Renderer::Machine::primary_descriptors(Launcher& launch, Frame& f, int round) {
  // Several ranks decide alike (on the longest pool of any): each builds the
  // descriptors of its own PEs from the same pixels, and the item buffer
  // passes, relayed between ranks, start on every rank in the same round.
  if ((group.all() ? f.pool_len : f.pool_len_max) >= flight.inject) return;
  if (f.next_pixel >= npix && f.sample + 1 < spp) {
    item_buffer(launch, ++f.sample);
    f.next_pixel = 0;
  }
  if (f.next_pixel >= npix) return;
  std::size_t count = std::min(flight.inject, npix - f.next_pixel);
  if (!group.all() && f.pool_len + count > pool.capacity) {
    DescriptorSet bigger;
    bigger.allocate(rt, (f.pool_len + count) * 3 / 2, "descriptor pool");
    pool.copy_prefix_to(rt, bigger, f.pool_len);
    pool = bigger;
  }
  if (f.pool_len + count > pool.capacity) count = pool.capacity - f.pool_len;
  kernels().primary.bind(fp, b_pes, b_item_tri, b_item_t, static_cast<int>(f.next_pixel), static_cast<int>(count),
                 offsets[std::size_t(f.sample % spp_k)], offsets[std::size_t(f.sample / spp_k)],
                 static_cast<int>(f.pool_len), pool, b_accum, b_hits);
  launch.run(kernels().primary.kernel(), "build_primary", round_up(count, 64), 0, round);
  f.next_pixel += count;
  f.pool_len += count;
}

}  // namespace opsila
