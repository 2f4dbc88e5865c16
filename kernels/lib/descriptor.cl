/* Ray descriptors as the kernels see them: the paper's six vectors, one
 * buffer per field (structure of arrays). */
#include "opsila_shared.h"

/* Descriptor structure-of-arrays: one buffer per field (the paper's vectors).
 *   org:  xyz origin, w = t_best (radiance) or t_max (shadow)
 *   dir:  xyz unit direction, w = entry distance of the PE named by cursor
 *   wgt:  xyz weight product (radiance) or light contribution (shadow)
 *   ids:  x = pixel, y = meta (kind | level << 2), z = best hit (global
 *         triangle, -1 none), w = cursor PE (last PE visited in entry order)
 *   dest: destination PE, -1 = NIL hole */
#define DESC_PARAMS(p) \
  __global float4 *p##_org, __global float4 *p##_dir, __global float4 *p##_wgt, __global int4 *p##_ids, \
      __global int *p##_dest
