// Scene distribution over the PEs' banks (facets never duplicated):
//  1. objects are cut into clusters: an object stays whole unless it has too
//     many facets or is much larger than a PE's region, in which case it is
//     split into spatially coherent pieces (median splits of its triangles);
//  2. space is cut into one region per PE by recursive bisection at the
//     facet-weighted median of the cluster centres (a k-d subdivision: regular
//     in structure, with equal shares of the scene rather than equal volumes);
//     each cluster lives in the bank of the region holding its centre;
//  3. each bank gets its own BVH (clusters at the top, facets below,
//     host/partition/bank_bvh.h), and every PE gets the bounding spheres and
//     the boxes (under one small BVH per PE) of all clusters.
//  4. what a facet needs to be shaded (vertex normals, texture coordinates,
//     the texels of its maps) goes into the bank that owns the facet.
#pragma once

#include <cstdint>
#include <vector>

#include "opsila_shared.h"
#include "partition/bank_array.h"
#include "scene/ray_sample.h"
#include "scene/scene.h"

namespace opsila {

struct BankedScene {
  int num_pes = 0;
  BankArray<BankTriangle> triangles;    // bank p: [pes[p].tri_begin, tri_end)
  BankArray<BankNode> nodes;            // bank p: [pes[p].node_begin, node_end), root first
  std::vector<Cluster> clusters;        // sorted by PE
  // Every instance's placement, owner and (in its bank) model BVH root
  // (opsila_shared.h, Instance; partition/instance_banks.h); global, like
  // the clusters. Empty for a scene without instances.
  std::vector<Instance> instances;
  // Routing BVH over padded cluster boxes: PE p's root is node p; nodes
  // P .. P + ceil(P / W) - 1 are the top level, W PEs' boxes to a node in PE
  // order (child = the PE, count 1; absent for an empty PE).
  BankArray<BankNode> route_nodes;
  std::vector<PeInfo> pes;
  std::vector<Material> materials;
  std::vector<Light> lights;
  // Empty, or one per triangle (same index): vertex normals, texture
  // coordinates and the bank's texture copies (see bank_attributes).
  BankArray<BankAttributes> attributes;
  std::vector<BankTexture> textures;   // texture copies, grouped by bank
  BankArray<std::uint32_t> texels;     // their texels, packed sRGB
  std::vector<std::uint64_t> bank_bytes;  // facets + BVH nodes + attributes + textures of each bank
  std::vector<std::uint64_t> texture_bytes;  // texture copies of each bank (part of bank_bytes)
  std::vector<std::uint64_t> bank_nodes;  // BVH nodes of each bank (part of bank_bytes, as BankNode)
  std::uint64_t texture_replicated_bytes = 0;  // every texture the facets use, once
  std::uint64_t global_bytes = 0;         // what every PE knows: spheres, routing boxes, PE boxes, materials, lights
  std::uint64_t replicated_bytes = 0;     // one full copy of the scene (what each PE would hold if duplicated)
  // For pilot frames (--balance measured; PartitionUse::pilot_maps, else
  // empty): the cluster of each bank facet and of each bank node (-1 for a
  // bank's nodes above its cluster roots), and the scene triangle of each
  // bank facet.
  std::vector<int> tri_cluster, node_cluster, source;
};

// split_flat: flat pieces are also cut to half a region across. Measured on
// hundreds and crowd (docs/BENCHMARKS.md): with routing on spheres it saves a
// quarter of the descriptors; with routing on boxes, which already fit flat
// pieces, it only adds clusters and routing work, so it is off there.
// sample: the frame's rays (scene/ray_sample.h); with it, regions share the
// expected work as well as the facets. measured: the work a pilot frame
// measured per facet and level; with it, each cut of the bisection balances
// every level's work (and a tenth on facets). Deterministic for equal inputs.
// use: what is kept beside the banks, and whether the scene's facets go.
struct PartitionUse {
  // Pilot frames (dist/pilot.h): BankedScene::source, tri_cluster and
  // node_cluster, which take the work they count back to clusters and
  // facets. A frame's banks need none of them (4 bytes a facet each).
  bool pilot_maps = false;
  // The scene itself, when its caller gives the facets up: they go once
  // the banks hold their copies, before the BVHs are built
  // (Scene::release_triangles keeps its figures), so that no facet is held
  // twice at the partition's peak.
  Scene* release = nullptr;
  // The devices the banks go to (MPI ranks, pe_group.h): their banks share
  // the copies of the models their instances place (partition/instance_banks.h).
  int ranks = 1;
};
BankedScene partition_scene(const Scene& scene, int num_pes, bool split_flat = false,
                            const RaySample* sample = nullptr, const MeasuredWork* measured = nullptr,
                            const PartitionUse& use = PartitionUse{});

// Per-frame constants for the kernels: the CONTRACT camera basis computed in
// float exactly as the formula reads, so that every renderer built on a
// banked scene casts the same primary rays bit for bit.
FrameParams frame_params(const Scene& scene, const BankedScene& bs, int bank_capacity);

}  // namespace opsila
