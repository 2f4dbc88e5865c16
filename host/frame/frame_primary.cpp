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
  const int blocks = static_cast<int>(ScatterPass::blocks_of(npix));
  frame_kernels::CountHitsArgs c;
  c.fp = fp;
  c.hits = item.tri;
  c.npix = pixels;
  c.traced = traced_rect;
  c.first_pass = sample == 0 ? 1 : 0;
  c.block_hits = b_hit_blocks;
  c.accum = b_accum;
  kernels().count_hits.bind(c);
  launch.run(kernels().count_hits.kernel(), "count_hits", round_up(blocks, 64), 0, -1);
  scatter->scan(launch, "hit_list_scan", b_hit_blocks, blocks, b_hit_total, -1);
  frame_kernels::ListHitsArgs l;
  l.hits = item.tri;
  l.npix = pixels;
  l.width = width;
  l.traced = traced_rect;
  l.block_first = b_hit_blocks;
  l.list = b_hit_pixels;
  kernels().list_hits.bind(l);
  launch.run(kernels().list_hits.kernel(), "list_hits", round_up(blocks, 64), 0, -1);
  cl_int listed = 0;
  launch.check(rt.queue().enqueueReadBuffer(b_hit_total, CL_TRUE, 0, sizeof(cl_int), &listed),
               "clEnqueueReadBuffer(hit list length)");
  return static_cast<std::size_t>(listed);
}

// The next `count` primary descriptors' build (at most that many: the
// pool's room), from the hit list's next hit on, after what waits in the
// pool; advances the frame past them.
frame_kernels::PrimaryBuildArgs Renderer::Machine::primary_build(Frame& f, std::size_t count) {
  if (!group.all() && f.pool_len + count > pool.capacity) {
    DescriptorSet bigger;
    bigger.allocate(rt, (f.pool_len + count) * 3 / 2, "descriptor pool");
    pool.copy_prefix_to(rt, bigger, f.pool_len);
    pool = bigger;
  }
  if (f.pool_len + count > pool.capacity) count = pool.capacity - f.pool_len;
  frame_kernels::PrimaryBuildArgs b;
  b.list = b_hit_pixels;
  b.hits = item.tri;
  b.distances = item.t;
  b.keys = item.key;
  b.first = static_cast<int>(f.next_hit);
  b.count = static_cast<int>(count);
  b.ox = offsets[std::size_t(f.sample % spp_k)];
  b.oy = offsets[std::size_t(f.sample / spp_k)];
  b.offset = static_cast<int>(f.pool_len);
  b.pool = pool;
  b.hit_count = b_hits;
  f.next_hit += count;
  f.pool_len += count;
  return b;
}

// Primary descriptors (SIMD), built from the hit list into the waiting pool
// when it runs short, bound for the PEs that own the items. When a sample
// pass is used up, the next sample's item buffer pass and hit list come
// first (the in-order queue runs them after the builds that read the
// previous ones), so the descriptors in flight stay bounded by the
// injection whatever N is. Nothing when the last SPMD launch built them
// (primary_ahead).
void Renderer::Machine::primary_descriptors(Launcher& launch, Frame& f, int round) {
  if (f.built_ahead) {
    f.built_ahead = false;
    return;
  }
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
  frame_kernels::PrimaryArgs a;
  a.fp = fp;
  a.pes = routing_tables.pes;
  a.insts = geometry.insts;
  a.build = primary_build(f, std::min(flight.inject, f.listed - f.next_hit));
  kernels().primary.bind(a);
  launch.run(kernels().primary.kernel(), "build_primary", round_up(std::size_t(a.build.count), 64), 0, round);
}

// The next round's primary descriptors, when that round would build them
// first thing, on one device (the ranks decide on every rank's pool, known
// only after this launch) and with no item buffer pass to run before them:
// the same descriptors in the same slots, built by the SPMD launch about to
// go, which saves the next round a launch. Their work-groups' count, or 0.
int Renderer::Machine::primary_ahead(Frame& f, frame_kernels::PrimaryBuildArgs& b) {
  b = primary_build(f, 0);  // the buffers, nothing to build
  if (!build_ahead || !group.all() || f.pool_len >= flight.inject || f.next_hit >= f.listed) return 0;
  b = primary_build(f, std::min(flight.inject, f.listed - f.next_hit));
  f.built_ahead = true;
  return static_cast<int>((std::size_t(b.count) + spmd_wg - 1) / spmd_wg);
}

}  // namespace opsila
