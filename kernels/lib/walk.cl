/* The traversal skeleton of every walk over wide BVH nodes (BankNode,
 * kernels/opsila_shared.h): the bank BVH's nearest-hit and any-hit walks
 * (lib/bvh.cl) and the routing walks (lib/routing.cl). Two parts, as in
 * Embree's split of a node intersector from the traverser:
 *   - the node test: node_spans below, the slab distances of a node's W
 *     child boxes for one ray, which each walk turns into entries and a mask
 *     of the children met (node_hits, route_hits);
 *   - the traverser: OPSILA_DEFINE_WALK, the stack, the order of the visit
 *     and what is pushed, written once; a walk brings its state and hooks.
 *
 * Node layout (built by host/partition/bank_bvh.cpp): OPSILA_BVH_WIDTH
 * children per node, their boxes stored per plane (lo_x[W], hi_x[W],
 * lo_y[W], ... ), then child[W] and count[W]:
 *   count == 0: inner node, child = node index;
 *   count >  0: leaf, items child .. child + count - 1;
 *   count <  0: empty slot, its box inverted (lo = +inf, hi = -inf,
 *              empty_node in host/partition/bank_bvh.h), which no ray meets:
 *              the node tests never read the counts.
 * A root has no box of its own: a walk starts by testing its children.
 * The bank walks may read the same nodes quantised (BankQNode, 128 bytes:
 * boxes on an 8-bit grid per node and axis, decoded exactly, rounded
 * outwards); there an empty slot's inverted box is finite, and a ray far
 * from a tiny node may round its two planes together and meet it: the
 * walk drops a met slot whose count is negative.
 *
 * PoCL does not vectorise these loops across work-items (divergent control
 * flow), so the width is used inside one work-item: the W child boxes of a
 * node are tested together, one floatW per plane. The host builder bounds
 * every path so that the private stack of OPSILA_BVH_STACK entries is
 * enough. */
#include "geometry.cl"

/* One more test (ray-box, ray-facet, destination) in *counter; nothing in a
 * program that does not count the work (OPSILA_COUNT_WORK,
 * kernels/opsila_shared.h). */
#define COUNT_TEST(counter) \
  do {                           \
    if (OPSILA_COUNT_WORK) ++*(counter); \
  } while (0)

#if OPSILA_BVH_WIDTH == 8
typedef float8 floatW;
typedef int8 intW;
#define vloadW vload8
#define convert_floatW convert_float8
#define convert_intW convert_int8
#define vstoreW vstore8
#else
typedef float4 floatW;
typedef int4 intW;
#define vloadW vload4
#define convert_floatW convert_float4
#define convert_intW convert_int4
#define vstoreW vstore4
#endif

/* A node test's lanes (-1 or 0 each) as a bit mask, bit k for lane k. */
OPSILA_INLINE uint lane_mask(intW m) {
#if OPSILA_BVH_WIDTH == 8
  int8 b = m & (int8)(1, 2, 4, 8, 16, 32, 64, 128);
  int4 h = b.lo | b.hi;
#else
  int4 h = m & (int4)(1, 2, 4, 8);
#endif
  int2 q = h.lo | h.hi;
  return (uint)(q.x | q.y);
}

/* The lowest set bit of a non-zero mask, its index: the walks take a mask's
 * children (or PEs) in increasing order, as a loop over k would. */
OPSILA_INLINE int lowest_bit(uint mask) { return 31 - clz(mask & (0u - mask)); }

/* The larger of a and b, b when a is NaN: one compare and select, which x86
 * does in one max instruction where fmax must also test for NaN. */
#define MAX_A_OR_B(a, b) select((b), (a), (a) > (b))
#define MIN_A_OR_B(a, b) select((b), (a), (a) < (b))

/* Slab distances of a node's child boxes, clamped to [tmin, tmax]: per
 * child, the largest of tmin and the plane entries, and the smallest of tmax
 * and the plane exits. Planes are taken near/far by the sign of the
 * direction, so one subtraction and one product per plane. A NaN (a ray in
 * a slab's boundary plane) is ignored, i.e. that slab counts as containing
 * the ray, as in ray_box_span. The bounds start from tmin and tmax, never
 * NaN, so each step is a compare and select (MAX_A_OR_B) with no NaN test;
 * the values are those of fmax and fmin (a maximum rounds nothing), only a
 * zero's sign may differ, which no comparison sees. -INFINITY and INFINITY
 * leave the distances unclamped (routing). */
/* The spans of the W boxes whose near and far planes are given, per axis. */
OPSILA_INLINE void plane_spans(const RayPre *r, floatW nx, floatW fx, floatW ny, floatW fy, floatW nz, floatW fz,
                               float tmin, float tmax, floatW *enter, floatW *leave) {
  floatW ox = (floatW)(r->org.x), oy = (floatW)(r->org.y), oz = (floatW)(r->org.z);
  floatW ix = (floatW)(r->inv_dir.x), iy = (floatW)(r->inv_dir.y), iz = (floatW)(r->inv_dir.z);
  floatW tnx = (nx - ox) * ix, tny = (ny - oy) * iy, tnz = (nz - oz) * iz;
  floatW tfx = (fx - ox) * ix, tfy = (fy - oy) * iy, tfz = (fz - oz) * iz;
  floatW e = (floatW)(tmin), l = (floatW)(tmax);
  e = MAX_A_OR_B(tnx, e);
  e = MAX_A_OR_B(tny, e);
  *enter = MAX_A_OR_B(tnz, e);
  l = MIN_A_OR_B(tfx, l);
  l = MIN_A_OR_B(tfy, l);
  *leave = MIN_A_OR_B(tfz, l);
}

OPSILA_INLINE void node_spans(const RayPre *r, __global const BankNode *nd, float tmin, float tmax, floatW *enter,
                              floatW *leave) {
  __global const float *nx = r->neg.x ? nd->hi_x : nd->lo_x, *fx = r->neg.x ? nd->lo_x : nd->hi_x;
  __global const float *ny = r->neg.y ? nd->hi_y : nd->lo_y, *fy = r->neg.y ? nd->lo_y : nd->hi_y;
  __global const float *nz = r->neg.z ? nd->hi_z : nd->lo_z, *fz = r->neg.z ? nd->lo_z : nd->hi_z;
  plane_spans(r, vloadW(0, nx), vloadW(0, fx), vloadW(0, ny), vloadW(0, fy), vloadW(0, nz), vloadW(0, fz), tmin,
              tmax, enter, leave);
}

/* A quantised node's planes (BankQNode): q * step + origin, exact, so the
 * spans are node_spans' on the boxes rounded outwards to the grid. */
OPSILA_INLINE floatW grid_plane(__global const opsila_u8 *q, float step, float origin) {
  return convert_floatW(vloadW(0, q)) * (floatW)(step) + (floatW)(origin);
}

OPSILA_INLINE void qnode_spans(const RayPre *r, __global const BankQNode *nd, float tmin, float tmax, floatW *enter,
                               floatW *leave) {
  float sx = as_float((uint)nd->exponent[0] << 23), sy = as_float((uint)nd->exponent[1] << 23),
        sz = as_float((uint)nd->exponent[2] << 23);
  float ox = nd->origin[0], oy = nd->origin[1], oz = nd->origin[2];
  __global const opsila_u8 *nx = r->neg.x ? nd->hi_x : nd->lo_x, *fx = r->neg.x ? nd->lo_x : nd->hi_x;
  __global const opsila_u8 *ny = r->neg.y ? nd->hi_y : nd->lo_y, *fy = r->neg.y ? nd->lo_y : nd->hi_y;
  __global const opsila_u8 *nz = r->neg.z ? nd->hi_z : nd->lo_z, *fz = r->neg.z ? nd->lo_z : nd->hi_z;
  plane_spans(r, grid_plane(nx, sx, ox), grid_plane(fx, sx, ox), grid_plane(ny, sy, oy), grid_plane(fy, sy, oy),
              grid_plane(nz, sz, oz), grid_plane(fz, sz, oz), tmin, tmax, enter, leave);
}

/* The nodes the bank walks read (the routing walks read BankNode): the
 * device's layout, and the mask of a node's slots in use (for the work
 * counters; an empty slot's box is inverted in both). */
#ifndef OPSILA_QUANT_NODES
#define OPSILA_QUANT_NODES 0
#endif
#if OPSILA_QUANT_NODES
typedef BankQNode WalkNode;
#define walk_node_spans qnode_spans
#define WALK_NODE_SLOTS(nd) lane_mask(convert_intW(vloadW(0, (nd)->lo_x)) <= convert_intW(vloadW(0, (nd)->hi_x)))
#else
typedef BankNode WalkNode;
#define walk_node_spans node_spans
#define WALK_NODE_SLOTS(nd) lane_mask(vloadW(0, (nd)->lo_x) <= vloadW(0, (nd)->hi_x))
#endif

/* OPSILA_DEFINE_WALK(name, State, Node, NODE, CHILD, LEAF, POP, ORDERED)
 * defines
 *   bool name(State *w, __global const Node *nodes, int root)
 * a depth-first walk below `root` (OpenCL C has no templates: the hooks are
 * functions named here, inlined into the walk):
 *   NODE(w, nd, float te[W]) -> uint: the node test; per child, its entry
 *     distance, and the mask of the children the ray meets (bit k: child k;
 *     empty slots never do). It counts the node's tests;
 *   CHILD(w, nd, k, count, entry): whether met child k is visited;
 *   LEAF(w, first, count, entry): a leaf's items; true ends the walk (and
 *     the walk returns true);
 *   POP(w, entry): ordered walks: whether an entry taken next is still
 *     worth visiting (it may set the bound the next NODE uses).
 * The children met are taken from the mask in increasing k (lowest set bit
 * first), the order a loop over k would give: a node's missed children cost
 * no branch (most of a node's eight are missed).
 * ORDERED 0: a met inner child is pushed, a met leaf visited at once; the
 *   last inner child met is visited next.
 * ORDERED 1: every met child, leaves too, is pushed, the children of one
 *   node farthest first (of equal entries, the later k nearer the top), so
 *   that the nearest is visited next; a leaf is visited when taken.
 * The child visited next is held in registers, never pushed: the stack sees
 * only the children left for later, in the same order as if every child
 * went through it (one store and load fewer per node, and the stack
 * bound of the builder holds with one entry to spare). A child that would
 * overflow the stack is dropped (the builder's bound makes that never
 * happen). */
#define OPSILA_DEFINE_WALK(name, State, Node, NODE, CHILD, LEAF, POP, ORDERED)     \
  OPSILA_INLINE bool name(State *w, __global const Node *nodes, int root) {      \
    int s_node[OPSILA_BVH_STACK], s_count[OPSILA_BVH_STACK];                      \
    float s_t[OPSILA_BVH_STACK];                                                  \
    int sp = 0;                                                                   \
    /* The child taken next: the root first. */                                  \
    int c_node = root, c_count = 0;                                               \
    float c_t = -INFINITY; /* its entry (ORDERED) */                             \
    bool have = !ORDERED || POP(w, c_t);                                          \
    for (;;) {                                                                    \
      if (!have) {                                                                \
        if (sp == 0) return false;                                                \
        --sp;                                                                     \
        if (ORDERED && !POP(w, s_t[sp])) continue;                                \
        c_node = s_node[sp];                                                      \
        c_count = ORDERED ? s_count[sp] : 0;                                      \
        if (ORDERED) c_t = s_t[sp];                                               \
      }                                                                           \
      have = false;                                                               \
      if (ORDERED && c_count > 0) {                                               \
        if (LEAF(w, c_node, c_count, c_t)) return true;                           \
        continue;                                                                 \
      }                                                                           \
      __global const Node *nd = &nodes[c_node];                                   \
      float te[OPSILA_BVH_WIDTH];                                                 \
      uint met = NODE(w, nd, te);                                                 \
      int base = sp;                                                              \
      while (met != 0u) {                                                         \
        int k = lowest_bit(met);                                                  \
        met &= met - 1u;                                                          \
        int cnt = nd->count[k];                                                   \
        /* An empty slot is met only by a NaN ray (it meets every box), or   \
         * a quantised one by rounding: taken as node child[k] it would start \
         * the walk again, without end. */                                     \
        if (cnt < 0 || !CHILD(w, nd, k, cnt, te[k])) continue;                    \
        int node = nd->child[k];                                                  \
        if (ORDERED) {                                                            \
          float t = te[k];                                                        \
          if (!have) {                                                            \
            have = true;                                                          \
            c_node = node, c_count = cnt, c_t = t;                                \
            continue;                                                             \
          }                                                                       \
          if (t <= c_t) { /* the new child is taken next; push the held one */    \
            float t0 = c_t;                                                       \
            int n0 = c_node, c0 = c_count;                                        \
            c_node = node, c_count = cnt, c_t = t;                                \
            node = n0, cnt = c0, t = t0;                                          \
          }                                                                       \
          if (sp >= OPSILA_BVH_STACK) continue;                                   \
          /* Insert, keeping this node's entries farthest first. */               \
          int j = sp++;                                                           \
          while (j > base && s_t[j - 1] < t) {                                    \
            s_t[j] = s_t[j - 1];                                                  \
            s_node[j] = s_node[j - 1];                                            \
            s_count[j] = s_count[j - 1];                                          \
            --j;                                                                  \
          }                                                                       \
          s_t[j] = t;                                                             \
          s_node[j] = node;                                                       \
          s_count[j] = cnt;                                                       \
          continue;                                                               \
        }                                                                         \
        if (cnt == 0) {                                                           \
          if (have && sp < OPSILA_BVH_STACK) s_node[sp++] = c_node;               \
          have = true;                                                            \
          c_node = node;                                                          \
          continue;                                                               \
        }                                                                         \
        if (LEAF(w, node, cnt, te[k])) return true;                               \
      }                                                                           \
      if (ORDERED && have && !POP(w, c_t)) have = false;                          \
    }                                                                             \
  }

/* POP of the unordered walks (never called). */
#define WALK_NO_POP(w, entry) true
