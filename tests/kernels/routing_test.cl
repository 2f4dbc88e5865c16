/* Test-only batch kernels for kernels/lib/routing.cl: the destination
 * choice alone, one work-item per ray, so that tests/kernels/routing_test.cpp
 * can hold it against a brute-force search over every PE's clusters on the
 * host. Ray i: origin org[i].xyz, unit direction dir[i].xyz, segment
 * (org[i].w, dir[i].w). */
#include "../../kernels/lib/routing.cl"

/* The whole ordered forwarding of each ray: next_destination from the
 * start (cursor -1, -1), then from each PE it names, until -1. visits[i *
 * num_pes + j] is the j-th PE (-1 after the last), entries the same for the
 * entry distances. */
__kernel void destination_chain(__global const PeInfo *pes, __global const Cluster *clusters,
                                __global const BankNode *route, int num_pes, int mode, __global const float4 *org,
                                __global const float4 *dir, int count, __global int *visits,
                                __global float *entries) {
  int i = get_global_id(0);
  if (i >= count) return;
  Routing rt = {pes, clusters, route, num_pes, mode};
  RayPre r = make_ray(org[i].xyz, dir[i].xyz);
  float cursor_t = -1.0f;
  int cursor_pe = -1;
  uint sphere_tests = 0u, route_tests = 0u;
  for (int j = 0; j < num_pes; ++j) {
    float entry = OPSILA_INF;
    int q = cursor_pe == -2 ? -1
                            : next_destination(&rt, &r, org[i].w, dir[i].w, cursor_t, cursor_pe, &entry,
                                               &sphere_tests, &route_tests);
    visits[(long)i * num_pes + j] = q;
    entries[(long)i * num_pes + j] = q >= 0 ? entry : OPSILA_INF;
    cursor_t = entry;
    cursor_pe = q >= 0 ? q : -2; /* -2: the chain has ended */
  }
}

/* The shadow rays' visits: next_shadow_destination from PE -1 on, never
 * `home`, in the order it names them (-1 after the last). */
__kernel void shadow_chain(__global const PeInfo *pes, __global const Cluster *clusters,
                           __global const BankNode *route, int num_pes, int mode, int home,
                           __global const float4 *org, __global const float4 *dir, int count,
                           __global int *visits) {
  int i = get_global_id(0);
  if (i >= count) return;
  Routing rt = {pes, clusters, route, num_pes, mode};
  RayPre r = make_ray(org[i].xyz, dir[i].xyz);
  uint sphere_tests = 0u, route_tests = 0u;
  int after = -1;
  for (int j = 0; j < num_pes; ++j) {
    int q = after == -2 ? -1
                        : next_shadow_destination(&rt, &r, org[i].w, dir[i].w, after, home, &sphere_tests,
                                                  &route_tests);
    visits[(long)i * num_pes + j] = q;
    after = q >= 0 ? q : -2;
  }
}

/* A new ray's first choice with its runner-up (first_destination), and what
 * a visit to that first PE would choose next with the limit dir[i].w:
 * out[i] = (first, runner-up or -1, known, the visit's choice) and
 * out_entries[i] = (first's entry, runner-up's, the visit choice's, 0). */
__kernel void first_two(__global const PeInfo *pes, __global const Cluster *clusters, __global const BankNode *route,
                        int num_pes, int mode, __global const float4 *org, __global const float4 *dir, int count,
                        __global int4 *out, __global float4 *out_entries) {
  int i = get_global_id(0);
  if (i >= count) return;
  Routing rt = {pes, clusters, route, num_pes, mode};
  RayPre r = make_ray(org[i].xyz, dir[i].xyz);
  uint sphere_tests = 0u, route_tests = 0u;
  float entry = OPSILA_INF, next_entry = OPSILA_INF;
  NextPe after;
  int first = first_destination(&rt, &r, org[i].w, &entry, &after, &sphere_tests, &route_tests);
  int next = first < 0 ? -1
                       : next_destination(&rt, &r, org[i].w, dir[i].w, entry, first, &next_entry, &sphere_tests,
                                          &route_tests);
  out[i] = (int4)(first, after.known ? after.pe : -1, after.known ? 1 : 0, next);
  out_entries[i] = (float4)(entry, after.known ? after.entry : OPSILA_INF, next >= 0 ? next_entry : OPSILA_INF, 0.0f);
}
