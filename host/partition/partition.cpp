#include "partition/partition.h"

#include "partition/bank_bvh.h"
#include "partition/instance_banks.h"
#include "partition/pe_group.h"
#include "partition/partition_steps.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <numeric>
#include <utility>
#include <vector>

#include "scene/camera.h"
#include "core/parallel.h"
#include "core/stage_clock.h"
#include "core/page_ledger.h"

namespace opsila {
namespace partition_steps {

namespace {

void put3(float* dst, const Vec3& v) {
  for (int a = 0; a < 3; ++a) dst[a] = v[a];
}

}  // namespace

float routing_sphere_radius(double radius, const Cluster& cl, const Box& sbox) {
  float magnitude = 0;
  for (int a = 0; a < 3; ++a) magnitude = std::max({magnitude, std::fabs(cl.bmin[a]), std::fabs(cl.bmax[a])});
  // 2e-5 of the magnitude: the boxes' 1e-5 on each axis, across a diagonal.
  return static_cast<float>(radius) * 1.0001f + 1e-5f * sbox.diagonal() + 2e-5f * magnitude;
}

// The routing tables every PE knows: for each PE, a BVH over its clusters'
// boxes, padded (like the spheres' radii) so that float rounding in the slab
// test never leaves a facet's hit point outside its cluster's box.
void build_routing(BankedScene& bs, const Box& sbox) {
  const float pad = 1e-5f * sbox.diagonal();
  const int top_nodes = (bs.num_pes + OPSILA_BVH_WIDTH - 1) / OPSILA_BVH_WIDTH;
  bs.route_nodes.resize(std::size_t(bs.num_pes) + top_nodes);
  for (int p = 0; p < bs.num_pes; ++p) {
    std::vector<Box> boxes;
    std::vector<int> ids;
    for (int c = bs.pes[p].cluster_begin; c < bs.pes[p].cluster_end; ++c) {
      const Cluster& cl = bs.clusters[c];
      Box b;
      for (int a = 0; a < 3; ++a) {
        float slack = pad + 1e-5f * std::max(std::fabs(cl.bmin[a]), std::fabs(cl.bmax[a]));
        b.lo[a] = cl.bmin[a] - slack;
        b.hi[a] = cl.bmax[a] + slack;
      }
      boxes.push_back(b);
      ids.push_back(c);
    }
    build_route_bvh(bs.route_nodes, p, boxes, ids);
  }
  // The top level: each PE's box is the union of its root's child boxes, so
  // (rounded slab distances being monotonic in the planes) its entry is
  // never above any of its clusters' and a PE it misses holds no box met.
  for (int i = 0; i < top_nodes; ++i) {
    BankNode& top = bs.route_nodes[std::size_t(bs.num_pes) + i];
    top = empty_node();
    for (int k = 0; k < OPSILA_BVH_WIDTH; ++k) {
      const int q = i * OPSILA_BVH_WIDTH + k;
      if (q >= bs.num_pes) continue;
      Box box;
      if (!children_box(bs.route_nodes[std::size_t(q)], box)) continue;
      top.lo_x[k] = box.lo[0], top.lo_y[k] = box.lo[1], top.lo_z[k] = box.lo[2];
      top.hi_x[k] = box.hi[0], top.hi_y[k] = box.hi[1], top.hi_z[k] = box.hi[2];
      top.child[k] = q;
      top.count[k] = 1;
    }
  }
}

// Vertex attributes and texture copies of every bank (CONTRACT "barycentric
// attributes", "Texture maps"): normals only when the scene is smooth, texture
// coordinates only where the facet's material has a map. A bank holds its
// own copy of each texture its facets use, as the paper's banks would, and
// its bytes count in bank_bytes and texture_bytes; but the banks that share
// a device share one copy of the texels (a copy per bank would multiply
// device memory by the PEs for nothing: 16 banks of one 256 MB map are 4 GB).
// Returns the bytes of one copy of every texture used.
std::uint64_t bank_attributes(const Scene& scene, const std::vector<int>& attributes, BankedScene& bs,
                              std::vector<char>* used_out) {
  const auto flags_of = [&](std::size_t k) {
    if (attributes.empty() || attributes[k] < 0) return 0;
    const VertexAttributes& a = scene.attributes[std::size_t(attributes[k])];
    const MaterialDesc& m = scene.materials[std::size_t(OPSILA_TRI_MATERIAL(bs.triangles[k]))];
    return (scene.smooth && a.has_normals ? OPSILA_ATTR_NORMALS : 0) |
           (a.has_uv && (m.map_kd >= 0 || m.map_ka >= 0) ? OPSILA_ATTR_UV : 0);
  };
  bs.texture_bytes.assign(bs.pes.size(), 0);
  bool any = false;
  for (std::size_t k = 0; k < attributes.size() && !any; ++k) any = flags_of(k) != 0;
  if (!any) {
    if (used_out) used_out->assign(scene.textures.size(), 0);
    return 0;
  }
  bs.attributes.assign(bs.triangles.size(), BankAttributes{});
  std::vector<char> used(scene.textures.size(), 0);
  std::vector<opsila_i32> texels_at(scene.textures.size(), -1);  // the device's one copy of each
  for (std::size_t p = 0; p < bs.pes.size(); ++p) {
    std::vector<int> copy(scene.textures.size(), -1);  // scene texture -> this bank's copy
    const auto bank_copy = [&](int texture) {
      if (texture < 0) return -1;
      if (copy[texture] < 0) {
        const Texture& tx = scene.textures[texture];
        if (texels_at[texture] < 0) {
          if (bs.texels.size() + tx.texels.size() > std::size_t(INT32_MAX))
            throw InputError("texture maps: " + tx.path + " (" + std::to_string(tx.texels.size() * 4) +
                             " bytes) brings the maps' texels past 2^31; use smaller images");
          texels_at[texture] = static_cast<opsila_i32>(bs.texels.size());
          bs.texels.insert(bs.texels.end(), tx.texels.begin(), tx.texels.end());
        }
        copy[texture] = static_cast<int>(bs.textures.size());
        bs.textures.push_back(BankTexture{texels_at[texture], tx.width, tx.height, static_cast<opsila_i32>(p)});
        bs.texture_bytes[p] += tx.texels.size() * sizeof(std::uint32_t) + sizeof(BankTexture);
        used[texture] = 1;
      }
      return copy[texture];
    };
    const PeInfo& pe = bs.pes[p];
    for (int k = pe.tri_begin; k < pe.tri_end; ++k) {
      BankAttributes& out = bs.attributes[std::size_t(k)];
      out.flags = flags_of(std::size_t(k));
      out.map_kd = out.map_ka = -1;
      if (out.flags == 0) continue;
      const VertexAttributes& a = scene.attributes[std::size_t(attributes[std::size_t(k)])];
      if (out.flags & OPSILA_ATTR_NORMALS) {
        put3(out.n0, a.normal[0]);
        put3(out.n1, a.normal[1]);
        put3(out.n2, a.normal[2]);
      }
      if (out.flags & OPSILA_ATTR_UV) {
        const MaterialDesc& m = scene.materials[std::size_t(OPSILA_TRI_MATERIAL(bs.triangles[std::size_t(k)]))];
        for (int c = 0; c < 3; ++c) out.uv[2 * c] = a.uv[c][0], out.uv[2 * c + 1] = a.uv[c][1];
        out.map_kd = bank_copy(m.map_kd);
        out.map_ka = bank_copy(m.map_ka);
      }
    }
    bs.bank_bytes[p] += std::uint64_t(pe.tri_end - pe.tri_begin) * sizeof(BankAttributes) + bs.texture_bytes[p];
  }
  if (used_out) *used_out = used;
  return texture_once(scene, used);
}

std::uint64_t texture_once(const Scene& scene, const std::vector<char>& used) {
  std::uint64_t once = 0;
  for (std::size_t t = 0; t < scene.textures.size() && t < used.size(); ++t)
    if (used[t])  // by its size: a rank of a scene read in shares decodes only the maps its facets use
      once += std::uint64_t(scene.textures[t].width) * std::uint64_t(scene.textures[t].height) *
                  sizeof(std::uint32_t) + sizeof(BankTexture);
  return once;
}

BankTriangle bank_triangle(const Triangle& t) {
  BankTriangle bt{};
  put3(bt.v0, t.v0);
  put3(bt.v1, t.v1);
  put3(bt.v2, t.v2);
  bt.facet_id = t.facet_id;
  bt.object_id = t.object_id;
  bt.material_fan = OPSILA_PACK_MATERIAL_FAN(t.material, t.fan);
  return bt;
}

namespace {

constexpr std::size_t kReleaseBatch = std::size_t(1) << 20;  // facets filled before their pages go

}  // namespace

// 3. Banks: triangles of each PE contiguous, cluster by cluster, and each
// cluster's bounding sphere. ranges[c] is cluster c's triangle range; the
// maps (FacetMaps) get what they were asked for. Clusters are filled side
// by side on the host threads, each into its own range, and each gives up
// its list of scene facets once copied. With `consume` (the scene's own
// triangles, when it gives them up) they are filled a batch of clusters at
// a time, and a page of the scene's triangles is handed back once every
// triangle on it is in a bank (core/page_ledger.h): the scene's copy
// shrinks while the banks' grows, instead of both being whole at once.
void fill_banks(const Scene& scene, const Box& sbox, std::vector<ClusterBuild>& cb, BankedScene& bs,
                FacetMaps& maps, std::vector<std::pair<int, int>>& ranges, std::vector<Triangle>* consume) {
  check_hit_order_ids(scene);
  ranges.resize(cb.size());
  int next = 0;
  for (std::size_t c = 0; c < cb.size(); ++c) {
    ranges[c] = {next, next + static_cast<int>(cb[c].tris.size())};
    next = ranges[c].second;
  }
  const std::size_t total = std::size_t(next);
  // A scene of one batch would give all its pages back at the end, as its
  // owner does right after: no ledger then (counting pages was a tenth of a
  // small scene's partition).
  if (total <= kReleaseBatch) consume = nullptr;
  bs.triangles.resize(total);
  if (maps.pilot) maps.source.resize(total), bs.tri_cluster.resize(total);
  if (!scene.attributes.empty()) maps.attributes.resize(total);
  bs.clusters.resize(cb.size());
  const auto fill_cluster = [&](std::size_t c) {
    const Vec3 ctr = cb[c].box.center();
    double r2 = 0;
    std::size_t k = std::size_t(ranges[c].first);
    for (int i : cb[c].tris) {
      const Triangle& t = scene.triangles[std::size_t(i)];
      bs.triangles[k] = bank_triangle(t);
      if (maps.pilot) maps.source[k] = i, bs.tri_cluster[k] = static_cast<int>(c);
      if (!maps.attributes.empty()) maps.attributes[k] = t.attributes;
      ++k;
      for (const Vec3* v : {&t.v0, &t.v1, &t.v2}) {
        double d2 = 0;
        for (int a = 0; a < 3; ++a) d2 += double((*v)[a] - ctr[a]) * double((*v)[a] - ctr[a]);
        r2 = std::max(r2, d2);
      }
    }
    if (!consume) cb[c].tris = std::vector<int>();
    Cluster& cl = bs.clusters[c];
    put3(cl.center, ctr);
    for (int a = 0; a < 3; ++a) {
      cl.bmin[a] = cb[c].box.lo[a];
      cl.bmax[a] = cb[c].box.hi[a];
    }
    cl.radius = routing_sphere_radius(std::sqrt(r2), cl, sbox);
    cl.pe = cb[c].pe;
    cl.root = -1;
  };
  if (!consume) return parallel_for(cb.size(), fill_cluster);
  PageLedger ledger(consume->data(), consume->size(), sizeof(Triangle));
  for (std::size_t c0 = 0, c1 = 0; c0 < cb.size(); c0 = c1) {
    while (c1 < cb.size() && (c1 == c0 || std::size_t(ranges[c1].first - ranges[c0].first) < kReleaseBatch)) ++c1;
    parallel_for(c1 - c0, [&](std::size_t c) { fill_cluster(c0 + c); });
    for (std::size_t c = c0; c < c1; ++c) {
      for (int i : cb[c].tris) ledger.done(std::size_t(i));
      cb[c].tris = std::vector<int>();
    }
    ledger.release();
  }
}

void pe_bounds(const std::vector<Cluster>& clusters, PeInfo& pe) {
  Box sb;
  for (int k = pe.cluster_begin; k < pe.cluster_end; ++k) {
    const Cluster& cl = clusters[std::size_t(k)];
    const Vec3 c{cl.center[0], cl.center[1], cl.center[2]};
    sb.grow(c - splat(cl.radius));
    sb.grow(c + splat(cl.radius));
  }
  const bool any = pe.cluster_begin < pe.cluster_end;
  for (int a = 0; a < 3; ++a) {
    pe.bmin[a] = any ? sb.lo[a] : 0.0f;
    pe.bmax[a] = any ? sb.hi[a] : 0.0f;
  }
}

// Each PE's range of clusters, triangles and bank BVH nodes, its bounds and
// its bank's size.
void describe_pes(const std::vector<ClusterBuild>& cb, const std::vector<std::pair<int, int>>& ranges,
                  FacetMaps& maps, std::size_t total, BankedScene& bs) {
  const int num_pes = bs.num_pes;
  bs.pes.resize(num_pes);
  std::vector<std::pair<int, int>> pe_clusters(static_cast<std::size_t>(num_pes));
  for (std::size_t p = 0, c = 0; p < pe_clusters.size(); ++p) {
    const std::size_t c_begin = c;
    while (c < cb.size() && cb[c].pe == static_cast<int>(p)) ++c;
    pe_clusters[p] = {static_cast<int>(c_begin), static_cast<int>(c)};
  }
  const std::vector<BankBvh> built =
      build_bank_bvhs(bs.nodes, bs.triangles, bs.clusters, pe_clusters, ranges, maps.follow());
  for (int p = 0; p < num_pes; ++p) {
    PeInfo& pe = bs.pes[p];
    const std::size_t c_begin = static_cast<std::size_t>(pe_clusters[p].first);
    const std::size_t c = static_cast<std::size_t>(pe_clusters[p].second);
    pe.cluster_begin = static_cast<int>(c_begin);
    pe.cluster_end = static_cast<int>(c);
    pe.tri_begin = c_begin < c ? ranges[c_begin].first : (c_begin < ranges.size() ? ranges[c_begin].first
                                                                                    : static_cast<int>(total));
    pe.tri_end = c_begin < c ? ranges[c - 1].second : pe.tri_begin;
    pe.node_begin = built[p].node_begin;
    pe.node_end = built[p].node_end;
    pe.instance_root = -1;  // instances: partition/instance_banks.h
    pe_bounds(bs.clusters, pe);
    std::uint64_t bytes = std::uint64_t(pe.tri_end - pe.tri_begin) * sizeof(BankTriangle) +
                          std::uint64_t(pe.node_end - pe.node_begin) * sizeof(BankNode);
    bs.bank_bytes.push_back(bytes);
    bs.bank_nodes.push_back(std::uint64_t(pe.node_end - pe.node_begin));
  }
}

// Materials and lights, which every PE reads.
void global_tables(const Scene& scene, BankedScene& bs) {
  for (const MaterialDesc& m : scene.materials) {
    Material g{};
    put3(g.ka, m.ka);
    put3(g.kd, m.kd);
    put3(g.ks, m.ks);
    put3(g.kr, m.kr());
    put3(g.kt, m.kt());
    g.ns = m.ns;
    g.ni = m.ni;
    bs.materials.push_back(g);
  }
  for (const LightDesc& l : scene.lights) {
    Light g{};
    put3(g.position, l.position);
    put3(g.intensity, l.intensity);
    bs.lights.push_back(g);
  }
}


// Each bank node's cluster: the nodes below a cluster's root are its own;
// a bank's nodes above its cluster roots belong to none (-1).
void node_clusters(BankedScene& bs) {
  bs.node_cluster.assign(bs.nodes.size(), -1);
  for (std::size_t c = 0; c < bs.clusters.size(); ++c) {
    std::vector<int> todo = {bs.clusters[c].root};
    while (!todo.empty()) {
      const int node = todo.back();
      todo.pop_back();
      if (node < 0) continue;
      bs.node_cluster[std::size_t(node)] = static_cast<int>(c);
      for (int k = 0; k < OPSILA_BVH_WIDTH; ++k)
        if (bs.nodes[std::size_t(node)].count[k] == 0) todo.push_back(bs.nodes[std::size_t(node)].child[k]);
    }
  }
}

void scene_bytes(BankedScene& bs, std::uint64_t texture_once) {
  bs.global_bytes = bs.clusters.size() * sizeof(Cluster) + bs.route_nodes.size() * sizeof(BankNode) +
                    bs.pes.size() * sizeof(PeInfo) +
                    bs.materials.size() * sizeof(Material) + bs.lights.size() * sizeof(Light);
  // One copy of everything: every bank's facets, nodes and attributes, but
  // each texture once (banks that share a texture each hold a copy).
  std::uint64_t all_banks = 0;
  for (std::size_t p = 0; p < bs.bank_bytes.size(); ++p) all_banks += bs.bank_bytes[p] - bs.texture_bytes[p];
  bs.texture_replicated_bytes = texture_once;
  bs.replicated_bytes = all_banks + texture_once + bs.global_bytes;
}

}  // namespace partition_steps

using namespace partition_steps;

BankedScene partition_scene(const Scene& scene, int num_pes, bool split_flat, const RaySample* sample,
                            const MeasuredWork* measured, const PartitionUse& use) {
  BankedScene bs;
  bs.num_pes = num_pes;
  Vec3 slo, shi;
  scene.bounds(slo, shi);
  Box sbox;
  sbox.grow(slo.data());
  sbox.grow(shi.data());

  StageClock clock(PrepareStage::partition);
  std::vector<ClusterBuild> cb = form_clusters(scene, sbox, num_pes, split_flat, sample, measured);
  clock.progress(0.6);  // roughly: the clusters and regions are most of it
  FacetMaps maps;
  maps.pilot = use.pilot_maps;
  std::vector<std::pair<int, int>> ranges;
  const std::size_t total = scene.triangles.size();
  if (use.release) use.release->keep_figures();  // before the fill gives the triangles' pages back
  fill_banks(scene, sbox, cb, bs, maps, ranges, use.release ? &use.release->triangles : nullptr);
  if (use.release) use.release->release_triangles();  // the banks hold them now
  clock.progress(0.8);
  describe_pes(cb, ranges, maps, total, bs);
  if (!scene.instances.empty())
    add_instance_banks(scene, deal_instances(scene, num_pes), 0, num_pes, sbox, bs, maps.attributes,
                       devices_of_pes(num_pes, use.ranks));

  build_routing(bs, sbox);
  if (use.pilot_maps) node_clusters(bs);
  const std::uint64_t once = bank_attributes(scene, maps.attributes, bs, nullptr);
  if (use.release) std::vector<VertexAttributes>().swap(use.release->attributes);
  bs.source = std::move(maps.source);
  global_tables(scene, bs);

  scene_bytes(bs, once);
  return bs;
}

// The frame's constants; the camera basis from scene/camera.h.
FrameParams frame_params(const Scene& scene, const BankedScene& bs, int bank_capacity) {
  FrameParams fp{};
  const CameraFrame cam = camera_frame(scene.camera, scene.width, scene.height);
  for (int a = 0; a < 3; ++a) {
    fp.eye[a] = cam.eye[a];
    fp.forward[a] = cam.forward[a];
    fp.right[a] = cam.right[a];
    fp.up[a] = cam.up[a];
    fp.ambient[a] = scene.ambient[a];
    fp.background[a] = scene.background[a];
  }
  fp.tan_half_fov = cam.tan_half_fov;
  fp.aspect = cam.aspect;
  {
    Vec3 lo, hi;
    scene.bounds(lo, hi);
    const double diagonal = box_diagonal(lo, hi);
    fp.epsilon = epsilon_for(diagonal);
    // The facet test's rounding follows the coordinates' magnitude (the
    // vertices are taken relative to the ray's origin): 2^-20 of it is some
    // 16 ulp, far above what was measured (2e-7 at coordinates of 10).
    float magnitude = 0;
    for (int a = 0; a < 3; ++a) magnitude = std::max({magnitude, std::fabs(lo[a]), std::fabs(hi[a])});
    fp.box_slack = std::ldexp(magnitude + static_cast<float>(diagonal), -20);
  }
  fp.width = scene.width;
  fp.height = scene.height;
  fp.max_depth = scene.max_depth;
  fp.num_lights = static_cast<int>(bs.lights.size());
  fp.num_pes = bs.num_pes;
  fp.num_clusters = static_cast<int>(bs.clusters.size());
  fp.bank_capacity = bank_capacity;
  fp.spawn_slots = OPSILA_SPAWN_SLOTS(fp.num_lights);
  fp.has_attributes = bs.attributes.empty() ? 0 : 1;
  // One device holds every PE; the renderer sets its PreparedBanks' group.
  fp.group_begin = 0;
  fp.group_end = bs.num_pes;
  fp.tri_base = 0;
  return fp;
}

}  // namespace opsila
