/* Test-only batch kernels for kernels/lib/bvh.cl: the bank BVH walks alone,
 * one work-item per ray, so that tests/kernels/bvh_test.cpp can hold each
 * answer against a brute-force search on the host. Ray i: origin org[i].xyz,
 * unit direction dir[i].xyz, segment (org[i].w, dir[i].w). */
#include "../../kernels/lib/bvh.cl"

/* traverse_nearest from `root`: the winning facet (-1: none), its distance,
 * and the (ray-facet, ray-box) tests the walk made. */
__kernel void nearest_batch(__global const WalkNode *nodes, __global const BankTriangle *tris, int root, float slack,
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
__kernel void any_batch(__global const WalkNode *nodes, __global const BankTriangle *tris, int root, float slack,
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

/* The facet tests in lanes (intersect_triangle2, intersect_triangle4) held
 * against intersect_triangle one facet at a time, bit for bit (a leaf's
 * winner must not depend on how its facets were tested): ray i on the
 * groups of four facets first[i] .. first[i] + groups - 1. Per ray: the
 * lane results whose bits differ from the single test's (0 expected), and
 * the single tests' hits. */
__kernel void facet_lanes_batch(__global const BankTriangle *tris, int num_groups, __global const float4 *org,
                                __global const float4 *dir, __global const int *first, int groups, int count,
                                __global uint2 *out) {
  int i = get_global_id(0);
  if (i >= count) return;
  RayPre r = make_ray(org[i].xyz, dir[i].xyz);
  float tmin = org[i].w, tmax = dir[i].w;
  uint differ = 0u, hits = 0u;
  for (int g = first[i]; g < min(first[i] + groups, num_groups); ++g) {
    __global const BankTriangle *q = &tris[4 * g];
    float one[4];
    for (int k = 0; k < 4; ++k) one[k] = intersect_triangle(&r, &q[k], tmin, tmax);
    float4 t4 = intersect_triangle4(&r, &q[0], &q[1], &q[2], &q[3], tmin, tmax);
    float2 a = intersect_triangle2(&r, &q[0], &q[1], tmin, tmax), b = intersect_triangle2(&r, &q[2], &q[3], tmin, tmax);
    float lanes[8] = {t4.x, t4.y, t4.z, t4.w, a.x, a.y, b.x, b.y};
    for (int k = 0; k < 8; ++k) differ += as_uint(lanes[k]) != as_uint(one[k % 4]) ? 1u : 0u;
    for (int k = 0; k < 4; ++k) hits += one[k] < INFINITY ? 1u : 0u;
  }
  out[i] = (uint2)(differ, hits);
}
