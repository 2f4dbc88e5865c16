/* SIMD phase 1: the item buffer. One work-item per pixel (per sample pass).
 * Each pixel is tested against the projected object (cluster) boxes, computed on the host
 * as pixel rectangles; inside a rectangle, the cluster's facet boxes (its BVH
 * nodes) and facets are tested with the pixel's primary ray. For a primary
 * ray, "pixel inside the projected box" and "ray meets the box" select the
 * same boxes, so the item is exactly the primary ray's nearest hit. In SIMD
 * mode every bank is reachable through the network, so no PE routing here.
 *
 * With N = k*k samples per pixel the pass runs once per sample (i, j), its
 * rays through (x + ox, y + oy), ox = (i+0.5)/k, oy = (j+0.5)/k: the nearest
 * hits (item_tri, item_t) become that sample's primary descriptors. The
 * (object, facet) output is the centre ray's, (0.5, 0.5): written by the
 * centre sample for odd k, by a pass of its own (no hits) for even k. */
#include "lib/bvh.cl"
#include "lib/camera.cl"

#define ITEM_TILE_MAX (OPSILA_ITEM_TILE_SIDE * OPSILA_ITEM_TILE_SIDE) /* pixels per tile, at most */

/* The best hit the groups of PEs before this one left (item_key: (facet,
 * fan), or (instance, fan | OPSILA_META_INSTANCE), as a descriptor carries
 * it): an instance's facet id is not needed here, since no other device
 * holds that instance. */
#define item_best(t, key)                                                                          \
  ((key).y & OPSILA_META_INSTANCE ? hit_key((t), (key).x, 0, (key).y & ~OPSILA_META_INSTANCE) \
                                  : hit_key((t), -1, (key).x, (key).y))

/* The clusters the bin of the tile at (x0, y0) lists: those whose
 * rectangle overlaps the bin, in the list's order (ItemBins,
 * host/frame/frame.h); *count of them. */
inline __global const int *tile_bin(__global const int *bin_first, __global const int *bin_list, int bin_side,
                                    int bins_x, int x0, int y0, int *count) {
  int bin = (y0 / bin_side) * bins_x + x0 / bin_side;
  *count = bin_first[bin + 1] - bin_first[bin];
  return bin_list + bin_first[bin];
}

/* The (object, facet) of the nearest hit: an instance's object, its
 * model's facet (opsila_shared.h, Instance). */
inline int2 item_pair(__global const BankTriangle *tris, __global const Instance *insts, HitKey best, int best_tri) {
  if (best_tri < 0) return (int2)(-1, -1);
  int object = best.inst < 0 ? tris[best_tri].object_id : insts[best.inst].object_id;
  return (int2)(object, tris[best_tri].facet_id);
}

/* One work-group = one square tile of tile_w x tile_w pixels, of the
 * tiles_x-wide grid of tiles from tile (tile_origin.x, tile_origin.y) on
 * (the host's traced rectangle: the pixels outside it are misses that no
 * kernel touches; the read-back gives them the background). `clusters`
 * and `cluster_rects` come nearest the eye first (item_depth_order,
 * host/frame/frame.h; cluster_near: each one's distance from the eye), so
 * that a near hit ends a pixel's search at the first cluster beyond it;
 * the hit order makes the items the same in any order. The group first
 * lists, in that order, the clusters of its bin (tile_bin) whose projected
 * box overlaps the tile (one rectangle test per cluster of the bin per
 * tile, instead of per cluster of the scene per pixel); each pixel then
 * tests only those rectangles and traces their facets.
 * listed_rect, the union of the rectangles (the host's), skips the listing
 * of a tile that no cluster can overlap: where the scene covers a small
 * part of the screen, most tiles; their pixels make no camera ray and only
 * write their misses. */
__kernel void item_buffer(FrameParams fp, __global const Cluster *clusters, __global const float *cluster_near,
                          __global const int4 *cluster_rects,
                          int4 listed_rect, __global const int *bin_first, __global const int *bin_list,
                          int bin_side, int bins_x, __global const WalkNode *nodes, __global const BankTriangle *tris,
                          __global const Instance *insts,
                          int tile_w, int2 tile_origin, int tiles_x, int tile_begin, float ox, float oy, int mode,
                          __global int2 *items,
                          __global int *item_tri, __global float *item_t, __global int2 *item_key) {
  __local int flags[ITEM_TILE_MAX];
  __local int list[OPSILA_ITEM_LIST_CAP];
  __local int listed;
  int lid = get_local_id(0), lsz = get_local_size(0);
  int tile = tile_begin + get_group_id(0);
  int x0 = (tile_origin.x + tile % tiles_x) * tile_w, y0 = (tile_origin.y + tile / tiles_x) * tile_w;
  int x1 = x0 + tile_w - 1, y1 = y0 + tile_w - 1;
  int x = x0 + lid % tile_w, y = y0 + lid / tile_w;
  bool inside = lid < tile_w * tile_w && x < fp.width && y < fp.height;
  int pixel = y * fp.width + x;
  /* A group of PEs after the first (an MPI rank) continues the nearest-hit
   * search from the state the groups before it left (with hits kept): the
   * least hit of all groups (host/frame/rank_exchange.h). */
  bool continued = fp.group_begin > 0 && inside;
  bool held = continued && item_tri[pixel] >= 0; /* a miss leaves no distance or key */
  HitKey best = held ? item_best(item_t[pixel], item_key[pixel]) : hit_none();
  int best_tri = -1; /* a facet of this group's banks (local index) that won */
  uint tri_tests = 0, box_tests = 0;
  CostProbe no_probe = no_cost_probe();
  if (lid == 0) listed = 0;
  barrier(CLK_LOCAL_MEM_FENCE);
  /* The same for every work-item of the group: the barriers below stay uniform. */
  bool tile_listed = !(x1 < listed_rect.x || x0 > listed_rect.z || y1 < listed_rect.y || y0 > listed_rect.w);
  RayPre r;
  if (tile_listed)
    r = make_ray(load3(fp.eye), primary_direction_at(fp, (float)min(x, fp.width - 1) + ox,
                                                     (float)min(y, fp.height - 1) + oy));
  int in_bin;
  __global const int *bin_clusters = tile_bin(bin_first, bin_list, bin_side, bins_x, x0, y0, &in_bin);
  for (int base = 0; tile_listed && base < in_bin; base += lsz) {
    flags[lid] = 0; /* else the cluster + 1 */
    if (base + lid < in_bin) {
      int c = bin_clusters[base + lid];
      int4 rect = cluster_rects[c];
      if (!(x1 < rect.x || x0 > rect.z || y1 < rect.y || y0 > rect.w)) flags[lid] = c + 1;
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    if (lid == 0) {
      int n = listed;
      for (int k = 0; k < lsz; ++k)
        if (flags[k]) list[n++] = flags[k] - 1;
      listed = n;
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    int n = listed;
    if (n > OPSILA_ITEM_LIST_CAP - lsz || base + lsz >= in_bin) {
      for (int i = 0; i < n && inside; ++i) {
        int cl = list[i];
        /* The list is nearest first: a cluster whose box lies beyond the
         * best hit's limit (with the culling slack) holds no winner, nor
         * does any after it. */
        if (cluster_near[cl] > cull_exit(hit_limit(best.t), fp.box_slack)) break;
        int4 pr = cluster_rects[cl]; /* x0, y0, x1, y1 inclusive */
        if (x < pr.x || x > pr.z || y < pr.y || y > pr.w) continue;
        cluster_nearest(&r, nodes, tris, insts, clusters[cl].root, 0.0f, fp.box_slack, &best, &best_tri, &tri_tests,
                         &box_tests, &no_probe);
      }
      barrier(CLK_LOCAL_MEM_FENCE);
      if (lid == 0) listed = 0;
      barrier(CLK_LOCAL_MEM_FENCE);
    }
  }
  if (!inside || (best_tri < 0 && continued)) return; /* nothing nearer here: the state stands */
  if (mode & OPSILA_ITEM_WRITE_ITEMS) items[pixel] = item_pair(tris, insts, best, best_tri);
  if (mode & OPSILA_ITEM_WRITE_HITS) {
    /* A miss writes only its -1: its distance and facet are never read
     * (here, in build_primary, or by the ranks after this one). */
    item_tri[pixel] = best_tri >= 0 ? fp.tri_base + best_tri : -1;
    if (best_tri >= 0) item_t[pixel] = best.t;
    if (best_tri >= 0) item_key[pixel] = best.inst < 0 ? (int2)(best.facet, best.fan) : (int2)(best.inst, best.fan | OPSILA_META_INSTANCE);
  }
}
