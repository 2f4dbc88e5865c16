/* opsila: data layouts shared by the host (C++17) and the kernels (OpenCL C 1.2).
 *
 * Everything that crosses the host/device boundary is declared here once.
 * Structs hold only 4-byte scalars and arrays of them (never float3/float4),
 * so that their layout is the same on both sides; the host checks sizes and
 * offsets with static_assert (see the bottom of this file).
 *
 * Paper terms: a PE (processing element) owns a memory bank, its slice of the
 * bank buffer; the work-groups that serve it each round work only on that
 * bank. A ray descriptor is one 64-byte record (OPSILA_DESCRIPTOR_LANES).
 */
#ifndef OPSILA_SHARED_H
#define OPSILA_SHARED_H

#ifdef __OPENCL_C_VERSION__
typedef int opsila_i32;
typedef uint opsila_u32;
typedef uchar opsila_u8;
#else
#include <cstddef>
#include <cstdint>
typedef std::int32_t opsila_i32;
typedef std::uint32_t opsila_u32;
typedef std::uint8_t opsila_u8;
#endif

/* Largest supported PE count (bounds per-PE scratch arrays). */
#define OPSILA_MAX_PES 1024
/* Largest supported --depth: levels are stored in OPSILA_LEVEL_BITS bits of
 * the descriptor's meta field, above the 2 kind bits. */
#define OPSILA_LEVEL_BITS 5
#define OPSILA_MAX_DEPTH ((1 << OPSILA_LEVEL_BITS) - 1)
/* Largest supported light count. */
#define OPSILA_MAX_LIGHTS 64
/* Stack depth of the BVH traversals: the host builder bounds every
 * root-to-leaf path so that 1 + sum(children - 1) never exceeds it. */
#define OPSILA_BVH_STACK 64
/* Pixel sums are accumulated as 64-bit fixed point with this many fraction
 * bits: integer addition is associative, so the image does not depend on the
 * order in which PEs or work-items finish (bit-identical runs). */
#define OPSILA_FIXED_SHIFT 24
#define OPSILA_FIXED_SCALE ((float)(1 << OPSILA_FIXED_SHIFT))
/* Pixel sums: 3 channels x (low, high) 32-bit words per pixel. */
#define OPSILA_ACCUM_WORDS 6

/* Scatter: pool entries per block of the count kernel (one work-item ranks
 * a block in order, which keeps the sort stable). */
#define OPSILA_SCATTER_BLOCK 256
/* Scatter: work-items per work-group of the scan and the plan at most;
 * their local arrays (the scan's sums, the plan's partial) hold one entry
 * per work-item. The host caps both work-groups at this. */
#define OPSILA_SCATTER_GROUP_MAX 256
/* Local memory of scatter_plan, in ints: partial, totals, group_base, the
 * flags and leaves_only. */
#define OPSILA_SCATTER_PLAN_LOCAL_INTS (OPSILA_SCATTER_GROUP_MAX + 3 * OPSILA_MAX_PES + 3)
/* Item buffer: square tiles of at most this many pixels a side (one
 * work-group per tile; smaller when the device allows fewer work-items). */
#define OPSILA_ITEM_TILE_SIDE 8
/* Item buffer: clusters a tile lists (local array) before it traces them;
 * a work-group adds at most one per work-item before the list is traced. */
#define OPSILA_ITEM_LIST_CAP 512

/* SPMD output: each work-item owns OPSILA_SPAWN_SLOTS(lights) output
 * places (fixed, so the output order is deterministic), enough for its most:
 * the descriptor sent on or the reflected ray, the transmitted ray, and one
 * shadow ray per light. It fills them from the front and says how many. */
#define OPSILA_SPAWN_SLOTS(lights) (2 + (lights))

/* PE x PE traffic matrices (per level) are counted up to this many PEs. */
#define OPSILA_TRAFFIC_MAX_PES 64

/* The ray descriptor, declared once: one 64-byte record of four 16-byte
 * lanes, X(lane, name, OpenCL type, host type). The paper keeps six vectors
 * (pixel and PE, level, direct intensity, direction, coefficient,
 * destination); a record moves as one contiguous 64-byte copy, one write
 * stream per destination bank instead of one per field (docs/BENCHMARKS.md).
 * The spare .w slots carry more than one meaning; kernels/lib/descriptor.cl
 * names each one (DESC_T_BEST, DESC_T_MAX, DESC_CURSOR_ENTRY, DESC_DEST...):
 *   org: xyz origin;    w: best hit distance so far (radiance) or the
 *                          distance to the light (shadow)
 *   dir: xyz direction; w: entry distance of the cursor PE (ordered forwarding)
 *   wgt: xyz weight product (radiance) or light contribution (shadow); w: 0
 *   ids: x pixel; y meta (kind | level << 2); z best hit (global triangle,
 *        -1 none; for a shadow ray, its home PE); w destination PE, which is also the cursor PE of ordered
 *        forwarding (-1: a NIL hole that the exchange skips) */
#define OPSILA_DESCRIPTOR_LANES(X) \
  X(0, org, float4, cl_float4)     \
  X(1, dir, float4, cl_float4)     \
  X(2, wgt, float4, cl_float4)     \
  X(3, ids, int4, cl_int4)
#define OPSILA_DESCRIPTOR_LANE_COUNT 4
#define OPSILA_DESCRIPTOR_BYTES 64

/* Item buffer pass modes (flags): write the (object, facet) output (the
 * centre ray's pass), and/or the nearest hits that a sample pass hands to
 * its primary descriptors. */
#define OPSILA_ITEM_WRITE_ITEMS 1
#define OPSILA_ITEM_WRITE_HITS 2

/* Descriptor kinds (low 2 bits of the meta field). */
#define OPSILA_KIND_NIL 0      /* hole: scatter skips it */
#define OPSILA_KIND_TRACE 1    /* radiance ray looking for its nearest hit */
#define OPSILA_KIND_RESOLVED 2 /* nearest hit known; goes to the owner PE to be shaded */
#define OPSILA_KIND_SHADOW 3   /* shadow ray carrying its light contribution */
#define OPSILA_META(kind, level) ((opsila_i32)((kind) | ((level) << 2)))
#define OPSILA_META_KIND(meta) ((meta)&3)
#define OPSILA_META_LEVEL(meta) (((meta) >> 2) & OPSILA_MAX_DEPTH)
/* A radiance ray's meta field also carries, above the level, the fan index
 * of its best hit so far (hit_order.h's third key; DESC_BEST_FACET holds
 * the second). */
#define OPSILA_META_FAN_SHIFT (OPSILA_LEVEL_BITS + 2)
#define OPSILA_META_WITH_FAN(meta, fan) ((opsila_i32)(((meta) & ((1 << OPSILA_META_FAN_SHIFT) - 1)) | (((fan) & (OPSILA_MAX_FAN - 1)) << OPSILA_META_FAN_SHIFT)))
#define OPSILA_META_FAN(meta) (((meta) >> OPSILA_META_FAN_SHIFT) & (OPSILA_MAX_FAN - 1))

/* The exchange's sort key of a record, which the dense destination stream
 * holds (DESC_PARAMS): 2 x its destination PE, plus 1 when the record can
 * still spawn radiance rays (not a shadow ray, and children are made below
 * its level: level + 1 < depth); -1 for a NIL hole. Per PE, the exchange
 * places first the records that end their ray tree, and while too many
 * wait only those (kernels/scatter.cl). */
#define OPSILA_STREAM_KEY(dest, meta, depth)                                                        \
  ((dest) < 0 ? -1                                                                                  \
              : 2 * (dest) + ((OPSILA_META_KIND(meta) != OPSILA_KIND_SHADOW && OPSILA_META_LEVEL(meta) + 1 < (depth)) ? 1 : 0))

/* Statistics counters per (level, PE), declared once, in index order:
 * X(NAME, "JSON name", SUM). The kernels count OPSILA_STAT_NAME; SUM says
 * which of the frame's totals the counter adds to: SPAWNED (descriptors
 * created at this level), FINISHED (descriptors that end here) or NONE.
 * The host takes the JSON names and the sums from here
 * (host/device/counters.h). A new counter is one line below. */
#define OPSILA_STAT_COUNTERS(X)                                                                            \
  X(TRACED, "traced", NONE)                     /* descriptors processed by the PE (any kind) */           \
  X(RADIANCE, "radiance", NONE)                 /* TRACE descriptors processed */                           \
  X(RESOLVED, "resolved", FINISHED)             /* radiance rays shaded here (hit found) */                 \
  X(SHADOW, "shadow", NONE)                     /* shadow descriptors processed */                          \
  X(TRI_TESTS, "triangle_tests", NONE)          /* ray-facet intersection tests */                          \
  X(BOX_TESTS, "box_tests", NONE)               /* ray-box tests in the bank BVH */                         \
  X(SPHERE_TESTS, "sphere_tests", NONE)         /* ray-bounding-sphere tests (destination choice) */        \
  X(SPAWN_RADIANCE, "spawned_radiance", SPAWNED) /* radiance rays spawned at this level (children) */       \
  X(SPAWN_SHADOW, "spawned_shadow", SPAWNED)    /* shadow rays spawned at this level */                     \
  X(MISS, "misses", FINISHED)                   /* radiance rays finished as misses */                      \
  X(OCCLUDED, "occluded", FINISHED)             /* shadow rays finished occluded */                         \
  X(LIT, "lit", FINISHED)                       /* shadow rays finished unoccluded */                       \
  X(FORWARD, "forwards", NONE)                  /* descriptors sent to another PE (or back to this one) */  \
  X(ROUTE_TESTS, "route_tests", NONE)           /* PE-box and routing-BVH node tests (destination choice) */ \
  X(LOCAL, "local", NONE)                       /* new rays tested in the spawning PE's own bank at once */
#define OPSILA_STAT_INDEX(name, json, sum) OPSILA_STAT_##name,
enum { OPSILA_STAT_COUNTERS(OPSILA_STAT_INDEX) OPSILA_STAT_COUNT };
#undef OPSILA_STAT_INDEX

/* The counters whose SUM is NONE measure the work (tests, forwards, kinds
 * processed): only --stats and the bench read them. A program built with
 * OPSILA_COUNT_WORK=0 (the render program when neither asks) leaves them,
 * the ray-box, ray-facet and destination tests and the PE x PE traffic out;
 * the spawned and finished counts (ray counts, progress) stay. Other
 * programs count everything. OPSILA_STAT_WORK_name is 1 for a work counter. */
#ifndef OPSILA_COUNT_WORK
#define OPSILA_COUNT_WORK 1
#endif
#define OPSILA_STAT_SUM_IS_WORK_NONE 1
#define OPSILA_STAT_SUM_IS_WORK_SPAWNED 0
#define OPSILA_STAT_SUM_IS_WORK_FINISHED 0
#define OPSILA_STAT_WORK_FLAG(name, json, sum) OPSILA_STAT_WORK_##name = OPSILA_STAT_SUM_IS_WORK_##sum,
enum { OPSILA_STAT_COUNTERS(OPSILA_STAT_WORK_FLAG) OPSILA_STAT_WORK_END };
#undef OPSILA_STAT_WORK_FLAG

/* Every counter the device accumulates over a frame (statistics, PE x PE
 * traffic, primary hits) is 64 bits wide, stored as two 32-bit words (low,
 * high) and added with add_fixed (kernels/lib/accum.cl): enough for the
 * largest frame accepted, 16384^2 pixels at 1024 samples (2^38 primary
 * rays), many times over. */
#define OPSILA_COUNTER_WORDS 2

/* Stage clocks: where the time of the SPMD phase and of the megakernel goes,
 * in cycles per stage, counted by a program built for it alone
 * (OPSILA_STAGE_CYCLES, kernels/lib/stage_cycles.cl; the bench's breakdown
 * frame), declared once in index order: X(NAME, "JSON name"). A stage's
 * cycles exclude those of the stages entered inside it. */
#define OPSILA_STAGES(X)                                                                          \
  X(BODY, "kernel_body")       /* the kernel's own: records loaded, rays set up, control */      \
  X(CAMERA, "camera")          /* the megakernel's camera rays and sample loop */                \
  X(BANK_WALK, "bank_walk")    /* nearest- and any-hit walks of a bank (megakernel: the scene) */ \
  X(DESTINATION, "destination") /* destination choice: the routing walks */                       \
  X(SHADING, "shading")        /* surface point, light terms, reflected and transmitted rays */  \
  X(PIXEL_SUMS, "pixel_sums")  /* fixed-point pixel sums */                                       \
  X(OUTPUTS, "outputs")        /* output records and their traffic counts */                      \
  X(STATISTICS, "statistics")  /* counters into the work-group's and the frame's */
#define OPSILA_STAGE_INDEX(name, json) OPSILA_STAGE_##name,
enum { OPSILA_STAGES(OPSILA_STAGE_INDEX) OPSILA_STAGE_COUNT };
#undef OPSILA_STAGE_INDEX
/* The counters a clocked frame fills: each stage's cycles, then how many
 * clock readings entered it (what the clock's own cost is charged to). */
#define OPSILA_STAGE_COUNTERS (2 * OPSILA_STAGE_COUNT)

/* One facet triangle as stored in a bank (48 bytes). Vertices are kept
 * exactly as loaded so that the watertight test sees shared edges alike.
 * material_fan: the material's index (low OPSILA_MATERIAL_BITS bits) and the
 * triangle's index in its facet's fan (the bits above), the hit order's
 * last key (hit_order.h); hence the two limits below. */
#define OPSILA_MATERIAL_BITS 16
#define OPSILA_MAX_MATERIALS (1 << OPSILA_MATERIAL_BITS)
#define OPSILA_MAX_FAN (1 << (32 - OPSILA_MATERIAL_BITS))
typedef struct {
  float v0[3];
  opsila_i32 facet_id; /* CONTRACT facet id (file order) */
  float v1[3];
  opsila_i32 object_id; /* CONTRACT object id */
  float v2[3];
  opsila_i32 material_fan; /* material | fan << OPSILA_MATERIAL_BITS */
} BankTriangle;
#define OPSILA_PACK_MATERIAL_FAN(material, fan) ((opsila_i32)((opsila_u32)(material) | ((opsila_u32)(fan) << OPSILA_MATERIAL_BITS)))
#define OPSILA_TRI_MATERIAL(tri) ((tri).material_fan & (OPSILA_MAX_MATERIALS - 1))
#define OPSILA_TRI_FAN(tri) ((opsila_i32)((opsila_u32)(tri).material_fan >> OPSILA_MATERIAL_BITS))

/* What the vertices of one bank triangle carry (CONTRACT "barycentric
 * attributes"), stored in the bank of the PE that owns the triangle, at the
 * triangle's own index. Present only when some triangle needs them
 * (FrameParams.has_attributes). 80 bytes. */
#define OPSILA_ATTR_NORMALS 1 /* n0..n2 hold vertex normals (smooth shading) */
#define OPSILA_ATTR_UV 2      /* uv holds texture coordinates and a map is set */
typedef struct {
  float n0[3];
  opsila_i32 flags;  /* OPSILA_ATTR_* */
  float n1[3];
  opsila_i32 map_kd; /* this bank's copy of the Kd map (BankTexture index), -1 none */
  float n2[3];
  opsila_i32 map_ka; /* this bank's copy of the Ka map, -1 none */
  float uv[6];       /* u0 v0 u1 v1 u2 v2 */
  float pad[2];
} BankAttributes;

/* A texture map copy held by one bank: texels [texel_begin, texel_begin +
 * width * height) of the texel array, row 0 the image's top row, each texel
 * 8-bit sRGB packed as r | g << 8 | b << 16. 16 bytes. */
typedef struct {
  opsila_i32 texel_begin;
  opsila_i32 width;
  opsila_i32 height;
  opsila_i32 pe; /* owning bank */
} BankTexture;

/* Bank BVH: wide nodes, OPSILA_BVH_WIDTH children each, child boxes stored
 * structure-of-arrays so that one work-item tests them all with one vector
 * slab test (kernels/lib/walk.cl documents the traversal that reads them).
 * Child k of a node:
 *   count[k] == 0: inner node, child[k] is its node index;
 *   count[k] >  0: leaf, facets child[k] .. child[k] + count[k] - 1;
 *   count[k] <  0: empty slot, with an inverted box (lo = +inf, hi = -inf,
 *                  host/partition/bank_bvh.h, empty_node) that no ray meets,
 *                  so the walks test all W boxes without reading the
 *                  counts.
 * Indices are global (bank offsets applied). The routing BVH (one per PE,
 * over its cluster boxes, see kernels/lib/routing.cl) uses the same node with
 * leaves of one cluster: child[k] is then a cluster index.
 * 8 children (256 bytes) measured faster than 4 on PoCL (docs/BENCHMARKS.md). */
#define OPSILA_BVH_WIDTH 8
typedef struct {
  float lo_x[OPSILA_BVH_WIDTH];
  float hi_x[OPSILA_BVH_WIDTH];
  float lo_y[OPSILA_BVH_WIDTH];
  float hi_y[OPSILA_BVH_WIDTH];
  float lo_z[OPSILA_BVH_WIDTH];
  float hi_z[OPSILA_BVH_WIDTH];
  opsila_i32 child[OPSILA_BVH_WIDTH];
  opsila_i32 count[OPSILA_BVH_WIDTH];
} BankNode;

/* The bank BVH's nodes on a device that reads them quantised
 * (OPSILA_QUANT_NODES, chosen by host/device/cl_runtime.cpp; built from
 * BankNode by host/partition/bank_qnode.cpp): 128 bytes instead of 256.
 * Each axis has a grid origin[a] + q * step, q = 0..255, step = 2^(e - 127)
 * with e = exponent[a]; the origin is a multiple of the step and every grid
 * point lies within 2^24 steps of 0, so each is a float and its decoding
 * (q * step + origin) is exact. A child's lo and hi are its BankNode box
 * rounded outwards to the grid: the walks test a box that holds the float
 * one, with the same slab arithmetic (kernels/lib/walk.cl). An empty slot
 * is inverted on every axis (lo 255, hi 0). child and count as BankNode's. */
typedef struct {
  float origin[3];
  opsila_u8 exponent[4]; /* [3] unused */
  opsila_u8 lo_x[OPSILA_BVH_WIDTH];
  opsila_u8 hi_x[OPSILA_BVH_WIDTH];
  opsila_u8 lo_y[OPSILA_BVH_WIDTH];
  opsila_u8 hi_y[OPSILA_BVH_WIDTH];
  opsila_u8 lo_z[OPSILA_BVH_WIDTH];
  opsila_u8 hi_z[OPSILA_BVH_WIDTH];
  opsila_i32 child[OPSILA_BVH_WIDTH];
  opsila_i32 count[OPSILA_BVH_WIDTH];
} BankQNode;

/* Destination choice: bounding spheres (the paper's scheme) or cluster boxes
 * through each PE's routing BVH. Same destinations rule, same image. */
#define OPSILA_ROUTING_SPHERES 0
#define OPSILA_ROUTING_BOXES 1

/* A cluster: the unit of distribution (an object, or a spatially coherent
 * piece of a large one). Its bounding sphere is known to every PE; its
 * facets live in one bank only. 48 bytes. */
typedef struct {
  float center[3];
  float radius;
  float bmin[3];
  opsila_i32 pe;   /* owning PE */
  float bmax[3];
  opsila_i32 root; /* root node of the cluster's BVH, global node index */
} Cluster;

/* Per-PE summary, global: box around all the PE's bounding spheres and its
 * range in the (PE-sorted) cluster and triangle tables. 64 bytes. */
typedef struct {
  float bmin[3];
  opsila_i32 cluster_begin;
  float bmax[3];
  opsila_i32 cluster_end;
  opsila_i32 tri_begin;
  opsila_i32 tri_end;
  opsila_i32 node_begin;
  opsila_i32 node_end;
  opsila_i32 instance_root; /* root of the BVH over this bank's instances, -1 none */
  opsila_i32 pad[3];
} PeInfo;

/* Instances (scenes/FORMAT.md "instances"): a model placed at many
 * transforms. The banks of a device that own instances of a model share
 * one copy of its facets and BVH (in the range of the first of them,
 * partition/instance_banks.h), and each holds a BVH over its instances
 * (PeInfo.instance_root) whose leaves are instances: a slot with count
 * OPSILA_INSTANCE_LEAF names instance child[k]. A hit on an instance is
 * shaded by the instance's PE (pe below). A ray meets an
 * instance in the model's frame, (to_object applied to its origin and
 * direction, not normalised, so distances along it are the world's).
 * Instance i is object num_objects + i (the scene's own objects first),
 * and its facets keep the model's facet ids (kernels/hit_order.h). The
 * table is global, like the clusters; root is only set on the device
 * that holds the instance's bank. 64 bytes. */
#define OPSILA_INSTANCE_LEAF 0x40000000
typedef struct {
  float to_object[12]; /* world to model: row i is (A[i][0], A[i][1], A[i][2], b[i]), x' = A x + b */
  opsila_i32 root;      /* the model's BVH root in this device's nodes, -1: not held here */
  opsila_i32 pe;        /* owning PE */
  opsila_i32 object_id; /* CONTRACT object id */
  opsila_i32 pad;
} Instance;
/* Whether the programs walk instances (-D, set when the scene has some):
 * a scene without them runs the walks it always ran. */
#ifndef OPSILA_INSTANCES
#define OPSILA_INSTANCES 0
#endif
/* A radiance ray's best hit lies on an instance: DESC_BEST_FACET then holds
 * the instance, and its facet id is read from the facet DESC_HIT names on
 * the device that holds it (the only one that can find another hit on that
 * instance, kernels/lib/descriptor.cl). Above the fan in the meta field. */
#define OPSILA_META_INSTANCE (1 << 30)

/* Material in docs/CONTRACT.md terms, with kr/kt already derived from illum. 80 bytes. */
typedef struct {
  float ka[3];
  float ns;
  float kd[3];
  float ni;
  float ks[3];
  float pad0;
  float kr[3];
  float pad1;
  float kt[3];
  float pad2;
} Material;

/* Point light, 32 bytes. */
typedef struct {
  float position[3];
  float pad0;
  float intensity[3];
  float pad1;
} Light;

/* Per-frame constants, passed by value to every kernel. */
typedef struct {
  float eye[3];
  float tan_half_fov; /* s */
  float forward[3];   /* f */
  float aspect;       /* a = W/H */
  float right[3];     /* r */
  float epsilon;      /* 1e-4 x scene diagonal */
  float up[3];        /* u */
  /* This device's group of PEs [group_begin, group_end) (all P on one
   * device; one contiguous group per MPI rank otherwise). Only its PEs have
   * banks here, and its facets are stored from index 0: a global triangle
   * index is tri_base + local index. */
  opsila_i32 group_begin;
  float ambient[3];
  opsila_i32 group_end;
  float background[3];
  opsila_i32 tri_base;
  opsila_i32 width;
  opsila_i32 height;
  opsila_i32 max_depth;
  opsila_i32 num_lights;
  opsila_i32 num_pes;
  opsila_i32 num_clusters;
  opsila_i32 bank_capacity; /* n: descriptor slots per bank */
  opsila_i32 spawn_slots;   /* S = lights + 2: output slots per processed descriptor */
  opsila_i32 has_attributes; /* 1: a BankAttributes per triangle */
  /* Absolute slack of the bank BVH's box culling (kernels/lib/bvh.cl,
   * node_hits): 2^-20 of the scene's largest coordinate plus its diagonal. */
  float box_slack;
  opsila_i32 pad3[2];
} FrameParams;

#ifndef __OPENCL_C_VERSION__
static_assert(sizeof(BankTriangle) == 48, "BankTriangle layout");
static_assert(OPSILA_ITEM_LIST_CAP > OPSILA_ITEM_TILE_SIDE * OPSILA_ITEM_TILE_SIDE,
              "a tile's work-items can each list a cluster before the list is traced");
static_assert(OPSILA_SCATTER_GROUP_MAX >= 1 && (OPSILA_SCATTER_GROUP_MAX & (OPSILA_SCATTER_GROUP_MAX - 1)) == 0,
              "the scatter's work-group cap is a power of two (queried sizes are rounded down to one)");
static_assert(offsetof(BankTriangle, facet_id) == 12, "BankTriangle layout");
static_assert(offsetof(BankTriangle, material_fan) == 44, "BankTriangle layout");
static_assert(OPSILA_META_FAN_SHIFT + (32 - OPSILA_MATERIAL_BITS) <= 31,
              "a fan index fits in the meta field above the kind and level");
static_assert(OPSILA_BVH_WIDTH == 4 || OPSILA_BVH_WIDTH == 8, "vector width of the node tests");
static_assert(sizeof(BankNode) == 32 * OPSILA_BVH_WIDTH, "BankNode layout");
static_assert(offsetof(BankNode, hi_x) == 4 * OPSILA_BVH_WIDTH, "BankNode layout");
static_assert(offsetof(BankNode, lo_z) == 16 * OPSILA_BVH_WIDTH, "BankNode layout");
static_assert(offsetof(BankNode, child) == 24 * OPSILA_BVH_WIDTH, "BankNode layout");
static_assert(offsetof(BankNode, count) == 28 * OPSILA_BVH_WIDTH, "BankNode layout");
static_assert(sizeof(BankQNode) == 16 + 14 * OPSILA_BVH_WIDTH, "BankQNode layout");
static_assert(offsetof(BankQNode, lo_x) == 16 && offsetof(BankQNode, child) == 16 + 6 * OPSILA_BVH_WIDTH,
              "BankQNode layout");
static_assert(sizeof(Cluster) == 48, "Cluster layout");
static_assert(offsetof(Cluster, pe) == 28, "Cluster layout");
static_assert(offsetof(Cluster, root) == 44, "Cluster layout");
static_assert(sizeof(PeInfo) == 64, "PeInfo layout");
static_assert(offsetof(PeInfo, instance_root) == 48, "PeInfo layout");
static_assert(sizeof(Instance) == 64, "Instance layout");
static_assert(offsetof(Instance, root) == 48, "Instance layout");
static_assert(OPSILA_META_FAN_SHIFT + (32 - OPSILA_MATERIAL_BITS) <= 30, "the instance flag lies above the fan");
static_assert(offsetof(PeInfo, tri_begin) == 32, "PeInfo layout");
static_assert(sizeof(Material) == 80, "Material layout");
static_assert(offsetof(Material, kt) == 64, "Material layout");
static_assert(sizeof(Light) == 32, "Light layout");
static_assert(sizeof(BankAttributes) == 80, "BankAttributes layout");
static_assert(offsetof(BankAttributes, map_ka) == 44, "BankAttributes layout");
static_assert(offsetof(BankAttributes, uv) == 48, "BankAttributes layout");
static_assert(sizeof(BankTexture) == 16, "BankTexture layout");
static_assert(sizeof(FrameParams) == 144, "FrameParams layout");
static_assert(offsetof(FrameParams, has_attributes) == 128, "FrameParams layout");
static_assert(offsetof(FrameParams, group_begin) == 60, "FrameParams layout");
static_assert(offsetof(FrameParams, tri_base) == 92, "FrameParams layout");
static_assert(offsetof(FrameParams, width) == 96, "FrameParams layout");
static_assert(offsetof(FrameParams, spawn_slots) == 124, "FrameParams layout");
static_assert(offsetof(FrameParams, box_slack) == 132, "FrameParams layout");
static_assert(OPSILA_FIXED_SCALE == 16777216.0f, "24 fraction bits");
static_assert(OPSILA_ACCUM_WORDS == 3 * 2, "3 channels of 64 bits in 32-bit words");
static_assert(OPSILA_LEVEL_BITS + 2 < 31, "kind and level fit in the meta field");
static_assert(OPSILA_META_LEVEL(OPSILA_META(OPSILA_KIND_SHADOW, OPSILA_MAX_DEPTH)) == OPSILA_MAX_DEPTH,
              "the deepest level survives the meta field");
static_assert((OPSILA_SCATTER_BLOCK & (OPSILA_SCATTER_BLOCK - 1)) == 0, "scatter block is a power of two");
#endif

#endif /* OPSILA_SHARED_H */
