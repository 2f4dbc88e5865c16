// The steps of partition_scene (partition/partition.cpp), for the collective
// partition of a scene read in shares (dist/collective_partition.cpp),
// which runs the same steps on each rank's part and so builds the same banks.
// Internal to host/machine.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "partition/bank_bvh.h"
#include "partition/partition.h"

namespace opsila {
namespace partition_steps {

struct ClusterBuild {
  std::vector<int> tris;  // indices into Scene::triangles
  double weight = 0;      // its share of the scene's expected work (region_weights)
  std::vector<double> work;  // measured: tests per level, then its facets' weight (region_weights)
  Box box;
  Vec3 c{0, 0, 0};  // centre for the spatial subdivision
  int pe = 0;
};

// How far objects are cut: into pieces of at most max_tris facets and (for
// more than one facet) a box diagonal of at most max_extent (half that for a
// flat piece with split_flat), from the whole scene's count and bounds.
struct SplitLimits {
  std::size_t max_tris = 0;
  float max_extent = 0;
};
SplitLimits split_limits(std::size_t total, const Box& sbox, int num_pes);
bool needs_cut(std::size_t facets, const Box& box, const SplitLimits& limits, bool split_flat);
// Inline: called per facet and axis at every cut (out of line, each call
// went through the shared library's symbol table).
inline Box tri_box(const Triangle& t) {
  Box b;
  b.grow(t.v0.data());
  b.grow(t.v1.data());
  b.grow(t.v2.data());
  return b;
}
inline float centroid(const Triangle& t, int a) { return (t.v0[a] + t.v1[a] + t.v2[a]) * (1.0f / 3.0f); }
void bounds_of(const Scene& scene, const std::vector<int>& tris, Box& box, Box& cbox);
ClusterBuild make_cluster(std::vector<int> tris, const Box& box);
// Cuts `tris` at the median centroid on the longest axis of `cbox` (ties by
// index); `tris` keeps the lower half. False when it cannot be cut.
bool cut_at_median(const Scene& scene, std::vector<int>& tris, const Box& cbox, std::vector<int>& upper);
// An object's triangles cut at median centroids (upper half first) into
// clusters appended to `out`; halves split side by side `spread` levels deep.
void split_object(const Scene& scene, std::vector<int> cur, std::size_t max_tris, float max_extent,
                  bool split_flat, std::vector<ClusterBuild>& out, int spread);
std::vector<std::vector<int>> triangles_by_object(const Scene& scene);
int split_threads();  // levels of split_object's halves to split side by side

// 1. Objects cut into clusters, in object order; `total` is the whole
// scene's triangle count (the pieces' size follows it).
std::vector<ClusterBuild> split_clusters(const Scene& scene, std::size_t total, const Box& sbox, int num_pes,
                                         bool split_flat);
// 2. Recursive bisection of the clusters' centres by weight into PEs
// [first, first + count); ties broken by the clusters' order.
void assign_regions(std::vector<ClusterBuild>& cl, std::vector<int> idx, int first, int count);
// Measured work (--balance measured) summed in fixed point, 2^-16 of a
// test: integer sums are the same in any order, so a cluster's work does
// not depend on the order of its facets nor on which rank holds which (a
// scene read in shares, dist/collective_balance.cpp). A pilot counts at
// most 2^32 tests per cluster and level, so a level's sum stays far below
// 2^63 while a pilot frame makes fewer than 2^47 tests at that level.
constexpr int kWorkFractionBits = 16;
// Per level, the measured work of facets `tris` (MeasuredWork::per_facet).
std::vector<std::int64_t> measured_sums(const MeasuredWork& m, const std::vector<int>& tris);
std::int64_t heat_of(const std::int64_t* sums, int levels);  // all levels' work
// Whether a cluster of `heat` is cut before the bisection (region_weights):
// hotter than half a PE's share of `all`.
bool too_hot(std::int64_t heat, std::int64_t all, int num_pes);
// A cluster's weights for assign_regions_measured: its work per level, then
// a tenth of the whole heat `all` in proportion to its facets.
std::vector<double> measured_weights(const std::int64_t* sums, int levels, std::int64_t all, std::size_t facets,
                                     std::size_t total_facets);
// Sampled rays (--balance work) whose segment crosses box b.
std::uint64_t crossings(const Box& b, const RaySample& sample);
// A cluster's weight for assign_regions with a ray sample: a tenth on its
// share of the facets, the rest on its share of the crossings `all`.
double sampled_weight(std::size_t facets, std::size_t total_facets, std::int64_t heat, std::int64_t all);
void assign_regions_measured(std::vector<ClusterBuild>& cl, std::vector<int> idx, int first, int count);
// 1-2. Clusters, weighted by expected work, bisected into PE regions; sorted
// by PE (partition_regions.cpp).
std::vector<ClusterBuild> form_clusters(const Scene& scene, const Box& sbox, int num_pes, bool split_flat,
                                        const RaySample* sample, const MeasuredWork* measured);
// Per bank facet, what follows it through the BVH build's reordering:
// the scene triangle it came from (for pilot frames, which spread the
// work they measure per cluster over the scene's facets) and its vertex
// attributes' index (when the scene has any). Neither is kept otherwise,
// so that a bank facet costs its 48 bytes and its share of the nodes.
struct FacetMaps {
  bool pilot = false;          // source and BankedScene::tri_cluster / node_cluster wanted
  std::vector<int> source;     // pilot: the scene triangle of each bank facet
  std::vector<int> attributes;  // Scene::attributes index of each bank facet, when the scene has any
  std::vector<std::vector<int>*> follow() { return {&source, &attributes}; }
};
// A scene triangle as a bank holds it.
BankTriangle bank_triangle(const Triangle& t);
// 3. The banks of clusters `cb` (sorted by PE, PEs 0 .. bs.num_pes - 1);
// the clusters' facet lists are given up once copied.
// `consume`: the scene's own triangles, given up (fill_banks, partition.cpp).
void fill_banks(const Scene& scene, const Box& sbox, std::vector<ClusterBuild>& cb, BankedScene& bs,
                FacetMaps& maps, std::vector<std::pair<int, int>>& ranges, std::vector<Triangle>* consume = nullptr);
void describe_pes(const std::vector<ClusterBuild>& cb, const std::vector<std::pair<int, int>>& ranges,
                  FacetMaps& maps, std::size_t total, BankedScene& bs);
// A PE's box: around its clusters' spheres (zero when it has none).
void pe_bounds(const std::vector<Cluster>& clusters, PeInfo& pe);
void node_clusters(BankedScene& bs);
// Vertex attributes and texture copies, from each bank facet's attributes
// index (FacetMaps::attributes, empty: none) and material; the scene's
// facets are not read. `used_out` (when given) gets which scene textures
// the banks use. Returns the bytes of one copy of each.
std::uint64_t bank_attributes(const Scene& scene, const std::vector<int>& attributes, BankedScene& bs,
                              std::vector<char>* used_out);
std::uint64_t texture_once(const Scene& scene, const std::vector<char>& used);
// 4. What every PE knows.
// A cluster's sphere radius for routing, from `radius` (the farthest vertex
// from cl.center, cl's box set): padded, as build_routing pads the cluster
// boxes, by 1e-5 of the scene's diagonal and of the coordinates' magnitude,
// so that float rounding in the sphere test never leaves a facet's hit
// outside it (at 1e6 a hit point is rounded by some 0.06, whatever the
// scene's size: a pad of the diagonal alone let --routing spheres skip a
// PE that held the winner, and the image changed with the PE count).
float routing_sphere_radius(double radius, const Cluster& cl, const Box& sbox);
void build_routing(BankedScene& bs, const Box& sbox);
void global_tables(const Scene& scene, BankedScene& bs);
void scene_bytes(BankedScene& bs, std::uint64_t texture_once);

}  // namespace partition_steps
}  // namespace opsila
