/* Primary descriptors, SIMD: built from the item buffer in the banks of the
 * PEs that own the items. */
#include "lib/routing.cl"
#include "lib/camera.cl"
#include "lib/accum.cl"

/* The hit list: the pixels of a sample pass whose primary ray hits, in
 * pixel order. Only they get primary descriptors; a miss is done here, so
 * the rounds of descriptors and exchanges never carry the misses (a view
 * where most rays miss costs the item buffer and little more). Two passes
 * over blocks of OPSILA_SCATTER_BLOCK pixels, one work-item a block, with
 * the exchange's scan between them (scatter_scan, one key):
 *   count_hits: the block's hits; a miss adds the background once over all
 *               groups of PEs (the device that holds PE 0), and only this
 *               work-item adds to the pixel in the launch. The frame's
 *               first pass (first_pass != 0) writes every pixel's sums instead of
 *               adding to them: the background or zero. The frame's pixel
 *               sums need no clearing before (a third of an all-miss frame's
 *               time on a CPU device: docs/BENCHMARKS.md, "Levers"); no
 *               descriptor has added to them yet. A pixel outside the
 *               traced rectangle is left alone: the host reads it as
 *               the background's sum (Renderer::Machine::read_image);
 *   list_hits:  the block's hit pixels, from the block's exclusive prefix on. */
__kernel void count_hits(FrameParams fp, __global const int *item_tri, int npix, int4 traced, int first_pass,
                         __global int *block_hits, volatile __global uint *accum) {
  int b = get_global_id(0);
  int first = b * OPSILA_SCATTER_BLOCK;
  if (first >= npix) return;
  int end = min(first + OPSILA_SCATTER_BLOCK, npix), hits = 0;
  /* fixed3 of a value >= 0 is below 2^63: written into zero sums, the same
   * words (no saturation bit) as accumulate_owned onto cleared ones. */
  long3 background = fp.group_begin == 0 ? fixed3(load3(fp.background)) : (long3)(0);
  for (int pixel = first; pixel < end; ++pixel) {
    if (!was_traced(pixel, fp.width, traced))
      continue; /* a miss in every pass, which the host's read-back gives the background */
    bool hit = item_tri[pixel] >= 0;
    hits += hit;
    if (first_pass)
      store_fixed3(accum, pixel, hit ? (long3)(0) : background);
    else if (!hit && fp.group_begin == 0)
      add_fixed3_owned(accum, pixel, background);
  }
  block_hits[b] = hits;
}

__kernel void list_hits(__global const int *item_tri, int npix, int width, int4 traced,
                        __global const int *block_first, __global int *hit_pixels) {
  int b = get_global_id(0);
  int first = b * OPSILA_SCATTER_BLOCK;
  if (first >= npix) return;
  int end = min(first + OPSILA_SCATTER_BLOCK, npix), at = block_first[b];
  for (int pixel = first; pixel < end; ++pixel)
    if (was_traced(pixel, width, traced) && item_tri[pixel] >= 0) hit_pixels[at++] = pixel;
}

/* From the hit list, primary ray descriptors are built for the banks of
 * the PEs that own the items: already RESOLVED (the nearest hit is known),
 * bound for the owner PE, which shades them. Hits first .. first + count - 1
 * of the list; written at queue[offset + k]. With several ranks, a hit that
 * another device's PE owns leaves a NIL hole here (destination -1): the
 * exchange reads no record of a hole. With several samples per pixel, the
 * item buffer holds one sample pass's hits, (ox, oy) is that sample's place
 * in the pixel, and the descriptor carries the pixel index: every sample
 * adds into the same pixel sums (divided by N when read). hit_count (64-bit
 * fixed pair) counts the descriptors built. item_key: the item buffer's
 * keys (kernels/item_buffer.cl), which say whether the hit is an instance's.
 * Built by this kernel, or by the previous round's SPMD launch in work-groups
 * of its own (kernels/spmd_phase.cl): one launch a round fewer. */
/* What a build reads besides the frame and the PE table (the arguments of
 * build_primary from hit_pixels to offset). */
typedef struct {
  __global const int *hit_pixels, *item_tri;
  __global const float *item_t;
  __global const int2 *item_key;
  int first, count;
  float ox, oy;
  int offset;
} PrimaryBuild;

/* Hit first + k's descriptor (none for k >= count); true when it was
 * built (a hit of another group's PE leaves a NIL hole). Always inlined:
 * PoCL called it otherwise, 1.5x the kernel's time. */
OPSILA_INLINE bool build_primary_one(FrameParams fp, __global const PeInfo *pes, __global const Instance *insts,
                                     const PrimaryBuild *pb, int k, DESC_PARAMS(q)) {
  if (k >= pb->count) return false;
  int pixel = pb->hit_pixels[pb->first + k];
  int slot = pb->offset + k;
  int tri = pb->item_tri[pixel];
  int2 key = pb->item_key[pixel];
  /* An instance's hit goes to the instance's PE (kernels/spmd_phase.cl). */
  int owner = key.y & OPSILA_META_INSTANCE ? insts[key.x].pe : owner_pe(pes, fp.num_pes, tri);
  if (owner < fp.group_begin || owner >= fp.group_end) {
    q_dest[slot] = -1;
    return false;
  }
  int x = pixel % fp.width, y = pixel / fp.width;
  float3 d = primary_direction_at(fp, (float)x + pb->ox, (float)y + pb->oy);
  Descriptor ds = make_descriptor(load3(fp.eye), pb->item_t[pixel], d, -1.0f, (float3)(1.0f), pixel,
                                  OPSILA_META(OPSILA_KIND_RESOLVED, 0), tri, owner);
  /* An instance's hit: the instance goes with it, to be shaded in its frame. */
  if (key.y & OPSILA_META_INSTANCE)
    desc_set_best(&ds, hit_key(pb->item_t[pixel], key.x, 0, key.y & ~OPSILA_META_INSTANCE));
  desc_store(q, q_dest, slot, ds, fp.max_depth);
  return true;
}

/* Work-group `group` of the SPMD launch's builders (kernels/spmd_phase.cl).
 * No barrier (PoCL 3.1 ran a barrier's tail in that branch for every
 * work-item as for the first): the host builds ahead on one device, where
 * every hit gets its descriptor, so the work-group's count is known. */
OPSILA_INLINE void build_primary_ahead(FrameParams fp, __global const PeInfo *pes, __global const Instance *insts,
                                       const PrimaryBuild *pb, int group, DESC_PARAMS(q),
                                       volatile __global uint *hit_count) {
  int lid = get_local_id(0), lsz = get_local_size(0);
  build_primary_one(fp, pes, insts, pb, group * lsz + lid, q, q_dest);
  if (lid == 0) count_add(hit_count, 0, (uint)clamp(pb->count - group * lsz, 0, lsz));
}

__kernel void build_primary(FrameParams fp, __global const PeInfo *pes, __global const Instance *insts,
                            __global const int *hit_pixels, __global const int *item_tri,
                            __global const float *item_t, __global const int2 *item_key, int first, int count,
                            float ox, float oy, int offset, DESC_PARAMS(q), volatile __global uint *hit_count) {
  __local uint hits;
  if (get_local_id(0) == 0) hits = 0u;
  barrier(CLK_LOCAL_MEM_FENCE);
  PrimaryBuild pb = {hit_pixels, item_tri, item_t, item_key, first, count, ox, oy, offset};
  if (build_primary_one(fp, pes, insts, &pb, get_global_id(0), q, q_dest)) atomic_inc(&hits);
  barrier(CLK_LOCAL_MEM_FENCE);
  if (get_local_id(0) == 0) count_add(hit_count, 0, hits);
}
