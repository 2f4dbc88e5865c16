/* Test-only batch kernels for kernels/lib/bvh.cl: the bank BVH walks alone,
 * one work-item per ray, so that tests/kernels/bvh_test.cpp can hold each
 * answer against a brute-force search on the host. Ray i: origin org[i].xyz,
 * unit direction dir[i].xyz, segment (org[i].w, dir[i].w). */
#include "../../kernels/lib/bvh.cl"

/* traverse_nearest from `root`: the winning facet (-1: none), its distance,
 * and the (ray-facet, ray-box) tests the walk made. */
__kernel void nearest_batch(__global const BankNode *nodes, __global const BankTriangle *tris, int root, float slack,
                            __global const float4 *org, __global const float4 *dir, int count,
                            __global int *hit_tri, __global float *hit_t, __global uint2 *tests) {
  int i = get_global_id(0);
  if (i >= count) return;
  RayPre r = make_ray(org[i].xyz, dir[i].xyz);
  HitKey best = hit_none();
  int tri = -1;
  uint tri_tests = 0u, box_tests = 0u;
  CostProbe probe = no_cost_probe();
  traverse_nearest(&r, nodes, tris, 0, root, org[i].w, slack, &best, &tri, &tri_tests, &box_tests, &probe);
  hit_tri[i] = tri;
  hit_t[i] = best.t;
  tests[i] = (uint2)(tri_tests, box_tests);
}

/* traverse_any over the segment: 1 when some facet is hit inside it. */
__kernel void any_batch(__global const BankNode *nodes, __global const BankTriangle *tris, int root, float slack,
                        __global const float4 *org, __global const float4 *dir, int count, __global int *blocked,
                        __global uint2 *tests) {
  int i = get_global_id(0);
  if (i >= count) return;
  RayPre r = make_ray(org[i].xyz, dir[i].xyz);
  uint tri_tests = 0u, box_tests = 0u;
  CostProbe probe = no_cost_probe();
  blocked[i] = traverse_any(&r, nodes, tris, 0, root, org[i].w, dir[i].w, slack, &tri_tests, &box_tests, &probe) ? 1 : 0;
  tests[i] = (uint2)(tri_tests, box_tests);
}
