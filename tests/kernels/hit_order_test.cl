/* Test-only batch kernel for kernels/hit_order.h: one work-item folds one
 * hit set in one order, so that tests/kernels/hit_order_test.cpp can check
 * that every order gives the host's winner. Set s holds hits
 * [s * n, s * n + n) of t and ids (facet, fan); work-item i folds set
 * set_of[i] in the order order[i * n + k], k = 0 .. n-1. */
#include "../../kernels/hit_order.h"

__kernel void least_hit_batch(__global const float *t, __global const int2 *ids, __global const int *set_of,
                              __global const int *order, int n, int count, __global int *winner) {
  int i = get_global_id(0);
  if (i >= count) return;
  int base = set_of[i] * n;
  HitKey best = hit_none();
  int won = -1;
  for (int k = 0; k < n; ++k) {
    int h = base + order[i * n + k];
    if (hit_before(t[h], -1, ids[h].x, ids[h].y, best)) {
      best = hit_key(t[h], -1, ids[h].x, ids[h].y);
      won = h - base;
    }
  }
  winner[i] = won;
}
