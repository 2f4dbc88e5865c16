/* Reference kernels for benchmarks: the device's plain copy bandwidth, the
 * physical ceiling of a scatter that moves the same bytes. */
#include "../opsila_shared.h"

__kernel void copy_float4(__global const float4 *src, __global float4 *dst, int count) {
  int i = get_global_id(0);
  if (i < count) dst[i] = src[i];
}
