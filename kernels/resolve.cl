/* The image on the device: each pixel's three sums (lib/accum.cl) to their
 * mean, the floats the host's decode gives (MeanDecoder in
 * host/core/fixed_point.h), for a device that does not share host memory:
 * it reads back 12 bytes a pixel, not the sums' 24, and the host decodes
 * nothing. The host's arithmetic is in doubles, so the kernel exists only
 * where the device has them (OPSILA_FP64); elsewhere the host decodes.
 * Every step is one IEEE operation, correctly rounded in OpenCL C as on the
 * host: the 64-bit sum to double, a product by the exact reciprocal (a power
 * of two samples) or a quotient, the double to float. A pixel outside the
 * traced rectangle (was_traced) holds no sums: it gets the background's,
 * `background`, as count_hits would have written them. */
#include "lib/accum.cl"

#ifndef OPSILA_FP64
#define OPSILA_FP64 0
#endif
#if OPSILA_FP64
#pragma OPENCL EXTENSION cl_khr_fp64 : enable

inline float resolve_mean(ulong sum, double divisor, double inverse, int exact) {
  /* A saturated sum (>= 2^63 - 1) reads as 2^63: what 2^63 - 1 rounds to
   * in a double. A min, not a select: PoCL's masked load for the select
   * stalled about 60 ns a value on the CPUs measured. */
  double s = convert_double(min(sum, (ulong)0x7fffffffffffffffUL));
  return convert_float(exact ? s * inverse : s / divisor);
}

/* A pixel's three values. */
inline void resolve_pixel(__global const uint *accum, int pixel, int width, int4 traced, ulong3 background,
                          double divisor, double inverse, int exact, __global float *rgb) {
  ulong3 sums = background;
  if (was_traced(pixel, width, traced)) {
    __global const uint *w = &accum[(long)pixel * OPSILA_ACCUM_WORDS];
    sums = (ulong3)(((ulong)w[1] << 32) | w[0], ((ulong)w[3] << 32) | w[2], ((ulong)w[5] << 32) | w[4]);
  }
  rgb[3L * pixel + 0] = resolve_mean(sums.x, divisor, inverse, exact);
  rgb[3L * pixel + 1] = resolve_mean(sums.y, divisor, inverse, exact);
  rgb[3L * pixel + 2] = resolve_mean(sums.z, divisor, inverse, exact);
}

/* A grid of a few work-groups per compute unit, each work-item taking every
 * grid's-size-th pixel: a CPU driver pays per work-group (PoCL: one a
 * pixel's 64 cost 0.4 s at 1920x1080), a GPU reads neighbours together. */
__kernel void resolve_image(__global const uint *accum, int npix, int width, int4 traced, ulong4 background,
                            double divisor, double inverse, int exact, __global float *rgb) {
  for (int pixel = get_global_id(0); pixel < npix; pixel += get_global_size(0))
    resolve_pixel(accum, pixel, width, traced, background.xyz, divisor, inverse, exact, rgb);
}
#endif
