/* Test-only batch kernel: the pixel sums' fixed-point conversion as the
 * kernels make it (fixed3, kernels/lib/accum.cl) beside OpenCL's own
 * convert_long3_sat_rte, which it spells out (tests/kernels/fixed_point_test.cpp). */
#include "../../kernels/lib/accum.cl"

__kernel void fixed_point_batch(__global const float *x, int count, __global long *fixed, __global long *builtin) {
  int i = get_global_id(0);
  if (i >= count) return;
  /* The value reaches the conversion as value * OPSILA_FIXED_SCALE, in each lane. */
  float3 v = (float3)(x[i], -x[i], x[i] * 0.5f);
  long3 q = fixed3(v), b = convert_long3_sat_rte(v * OPSILA_FIXED_SCALE);
  vstore3(q, i, fixed);
  vstore3(b, i, builtin);
}
