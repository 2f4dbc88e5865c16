/* Reference kernels for benchmarks: the device's plain copy bandwidth, the
 * physical ceiling of a scatter that moves the same bytes. */
#include "../opsila_shared.h"

__kernel void copy_float4(__global const float4 *src, __global float4 *dst, int count) {
  int i = get_global_id(0);
  if (i < count) dst[i] = src[i];
}

/* The paper's scatter primitive, Vd(I(i)) = Vs(i) with I injective and
 * given (I(i) < 0: a NIL hole, skipped), on the paper's six vectors: pixel
 * and PE, level, direct intensity, direction, coefficient, destination.
 * 8 + 4 + 16 + 16 + 16 + 4 = 64 bytes per descriptor, six read and six
 * write streams: the reference point for the renderer's one-record move. */
__kernel void scatter_six_vectors(int count, __global const int *index, __global const int2 *s_pixel,
                                  __global const int *s_level, __global const float4 *s_light,
                                  __global const float4 *s_dir, __global const float4 *s_coef,
                                  __global const int *s_dest, __global int2 *d_pixel, __global int *d_level,
                                  __global float4 *d_light, __global float4 *d_dir, __global float4 *d_coef,
                                  __global int *d_dest) {
  int i = get_global_id(0);
  if (i >= count) return;
  int j = index[i];
  if (j < 0) return;
  d_pixel[j] = s_pixel[i];
  d_level[j] = s_level[i];
  d_light[j] = s_light[i];
  d_dir[j] = s_dir[i];
  d_coef[j] = s_coef[i];
  d_dest[j] = s_dest[i];
}

/* The same primitive on one 64-byte record per descriptor (four float4). */
__kernel void scatter_one_record(int count, __global const int *index, __global const float4 *src,
                                 __global float4 *dst) {
  int i = get_global_id(0);
  if (i >= count) return;
  int j = index[i];
  if (j < 0) return;
  for (int lane = 0; lane < 4; ++lane) dst[(long)j * 4 + lane] = src[(long)i * 4 + lane];
}
