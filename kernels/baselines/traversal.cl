/* Traversal alone, for the bench: the rays a megakernel run traced
 * (megakernel_rays), traced again through the same BVH with nothing else:
 * no camera, shading, accumulation or output beyond one word per ray. What
 * every other figure of the bench spends per ray beyond this is shading,
 * accumulation and (OPSILA) exchange. Ray i: rays[2i] = (origin, tmin),
 * rays[2i + 1] = (direction, tmax); the nearest-hit kernel ignores tmax.
 * root_lo, root_hi: the union of the root's child boxes (scene_nearest);
 * inst_root: the instances' BVH (-1: none). */
#include "../lib/bvh.cl"

/* Nearest hit: the winning facet, -1 for none. */
__kernel void traversal_nearest(__global const WalkNode *nodes, __global const BankTriangle *tris,
                                __global const Instance *insts, int root,
                                float4 root_lo, float4 root_hi, int inst_root, float slack, __global const float4 *rays, int count,
                                __global int *hit) {
  int i = get_global_id(0);
  if (i >= count) return;
  float4 o = rays[2 * i], d = rays[2 * i + 1];
  RayPre r = make_ray(o.xyz, d.xyz);
  HitKey best = hit_none();
  int tri = -1;
  uint tri_tests = 0u, box_tests = 0u; /* unread: the compiler may drop the counting */
  CostProbe probe = no_cost_probe();
  scene_nearest(&r, nodes, tris, insts, root, root_lo.xyz, root_hi.xyz, o.w, slack, &best, &tri, &tri_tests, &box_tests,
                &probe);
  if (OPSILA_INSTANCES && inst_root >= 0)
    traverse_nearest(&r, nodes, tris, insts, inst_root, o.w, slack, &best, &tri, &tri_tests, &box_tests, &probe);
  hit[i] = tri;
}

/* Any hit in (tmin, tmax): 1 when the segment is blocked. */
__kernel void traversal_any(__global const WalkNode *nodes, __global const BankTriangle *tris,
                            __global const Instance *insts, int root, float4 root_lo,
                            float4 root_hi, int inst_root, float slack, __global const float4 *rays, int count, __global int *hit) {
  int i = get_global_id(0);
  if (i >= count) return;
  float4 o = rays[2 * i], d = rays[2 * i + 1];
  RayPre r = make_ray(o.xyz, d.xyz);
  uint tri_tests = 0u, box_tests = 0u;
  CostProbe probe = no_cost_probe();
  bool blocked =
      scene_any(&r, nodes, tris, insts, root, root_lo.xyz, root_hi.xyz, o.w, d.w, slack, &tri_tests, &box_tests, &probe);
  if (OPSILA_INSTANCES && !blocked && inst_root >= 0)
    blocked = traverse_any(&r, nodes, tris, insts, inst_root, o.w, d.w, slack, &tri_tests, &box_tests, &probe);
  hit[i] = blocked ? 1 : 0;
}
