/* Test-only batch kernel for kernels/lib/shading.cl's specular power, as
 * light_term takes it: out[i] = specular_pow(x[i], y[i]) (see
 * tests/kernels/shading_test.cpp). */
#include "../../kernels/lib/bvh.cl"
#include "../../kernels/lib/shading.cl"

__kernel void specular_pow_batch(__global const float *x, __global const float *y, int count, __global float *out) {
  int i = get_global_id(0);
  if (i < count) out[i] = specular_pow(x[i], y[i]);
}
