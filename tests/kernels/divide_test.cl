/* Test-only batch kernel for the arithmetic the host and every device must
 * share: quotient, reciprocal (the slab inverse 1 / d) and square root, as
 * the kernels write them (see tests/kernels/divide_test.cpp). */
#include "../../kernels/lib/geometry.cl"

__kernel void divide_batch(__global const float *x, __global const float *y, int count, __global float *quotient,
                           __global float *inverse, __global float *root) {
  int i = get_global_id(0);
  if (i >= count) return;
  quotient[i] = x[i] / y[i];
  inverse[i] = 1.0f / y[i];
  root[i] = sqrt(x[i]);
}

/* Lengths and unit vectors (len3, unit3), against the host's vec.h. */
__kernel void unit_batch(__global const float *v, int count, __global float *len, __global float *unit) {
  int i = get_global_id(0);
  if (i >= count) return;
  float3 a = vload3(i, v);
  len[i] = len3(a);
  vstore3(unit3(a), i, unit);
}
