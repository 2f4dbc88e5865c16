/* Any-hit batches for tinybvh's traversal functions (its traverse.cl has
 * nearest-hit batches only): the segment's end in D.w, answer 1 or 0 in
 * hit.x. Built with tinybvh's traverse.cl on its include path. */
#include "traverse.cl"

void kernel occluded_gpu4way(const global float4 *nodes, global struct Ray *rays) {
  const unsigned i = get_global_id(0);
  rays[i].hit.x = isoccluded_gpu4way(nodes, rays[i].O.xyz, rays[i].D.xyz, rays[i].rD.xyz, rays[i].D.w) ? 1 : 0;
}

void kernel occluded_cwbvh(global const float4 *nodes, global const float4 *tris, global struct Ray *rays) {
  const unsigned i = get_global_id(0);
#ifdef SIMD_AABBTEST
  float4 o = rays[i].O, d = rays[i].D, rd = rays[i].rD;
  const float tmax = d.w;
  o.w = 1, d.w = 0, rd.w = 1;
  rays[i].hit.x = isoccluded_cwbvh(nodes, tris, o, d, rd, tmax) ? 1 : 0;
#else
  rays[i].hit.x = isoccluded_cwbvh(nodes, tris, rays[i].O.xyz, rays[i].D.xyz, rays[i].rD.xyz, rays[i].D.w) ? 1 : 0;
#endif
}

void kernel occluded_ailalaine(const global struct BVHNode *nodes, const global uint *idx, const global float4 *verts,
                               global struct Ray *rays) {
  const unsigned i = get_global_id(0);
  rays[i].hit.x =
      isoccluded_ailalaine(nodes, idx, verts, 0, rays[i].O.xyz, rays[i].D.xyz, rays[i].rD.xyz, rays[i].D.w) ? 1 : 0;
}
