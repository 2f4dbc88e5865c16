/* Primary descriptors, SIMD: built from the item buffer in the banks of the
 * PEs that own the items. */
#include "lib/routing.cl"
#include "lib/camera.cl"
#include "lib/accum.cl"

/* From the item buffer, primary ray descriptors are built for the banks of
 * the PEs that own the items: already RESOLVED (the nearest hit is known),
 * bound for the owner PE, which shades them. Misses add the background and
 * leave a NIL hole (destination -1). Written at queue[offset + k]. With
 * several samples per pixel, the item buffer holds one sample pass's hits,
 * (ox, oy) is that sample's place in the pixel, and the descriptor carries
 * the pixel index: every sample adds into the same pixel sums (divided by N
 * when read). hit_count (64-bit fixed pair) counts the descriptors built. */
__kernel void build_primary(FrameParams fp, __global const PeInfo *pes, __global const int *item_tri,
                            __global const float *item_t, int pixel_begin, int pixel_count, float ox, float oy,
                            int offset, DESC_PARAMS(q), volatile __global uint *accum,
                            volatile __global uint *hit_count) {
  __local uint hits;
  if (get_local_id(0) == 0) hits = 0u;
  barrier(CLK_LOCAL_MEM_FENCE);
  int k = get_global_id(0);
  if (k < pixel_count) {
    int pixel = pixel_begin + k;
    int slot = offset + k;
    int tri = item_tri[pixel];
    int owner = tri >= 0 ? owner_pe(pes, fp.num_pes, tri) : -1;
    if (tri < 0 || owner < fp.group_begin || owner >= fp.group_end) {
      /* A miss adds the background once over all groups of PEs (this
       * work-item alone adds to its pixel in this launch); a hit is built by
       * the device that holds its owner PE. A NIL hole is its destination
       * alone: the exchange reads no record of a hole. */
      if (tri < 0 && fp.group_begin == 0) accumulate_owned(accum, pixel, load3(fp.background));
      q_dest[slot] = -1;
    } else {
      int x = pixel % fp.width, y = pixel / fp.width;
      float3 d = primary_direction_at(fp, (float)x + ox, (float)y + oy);
      desc_store(q, q_dest, slot, make_descriptor(load3(fp.eye), item_t[pixel], d, -1.0f, (float3)(1.0f), pixel,
                                          OPSILA_META(OPSILA_KIND_RESOLVED, 0), tri, owner), fp.max_depth);
      atomic_inc(&hits);
    }
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  if (get_local_id(0) == 0) count_add(hit_count, 0, hits);
}
