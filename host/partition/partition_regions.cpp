// Step 2 of the partition: each cluster's expected work (its facets, the
// sampled rays that cross it, or a pilot frame's measured tests) and the
// recursive bisection of the clusters into PE regions by that work.
#include "partition/partition_steps.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <utility>
#include <vector>

#include "scene/camera.h"

namespace opsila {
namespace partition_steps {

// Recursive bisection of the cluster centres, weighted by expected work
// (region_weights), into `count` regions starting at PE `first`.
void assign_regions(std::vector<ClusterBuild>& cl, std::vector<int> idx, int first, int count) {
  if (idx.empty()) return;
  if (count == 1) {
    for (int i : idx) cl[i].pe = first;
    return;
  }
  Box cbox;
  for (int i : idx) cbox.grow(cl[i].c);
  int axis = cbox.longest();
  std::sort(idx.begin(), idx.end(), [&](int a, int b) {
    return cl[a].c[axis] < cl[b].c[axis] || (cl[a].c[axis] == cl[b].c[axis] && a < b);
  });
  int left = count / 2;
  double total = 0;
  for (int i : idx) total += cl[i].weight;
  double target = total * left / count, acc = 0;
  std::size_t cut = 0;
  while (cut < idx.size() && acc + 0.5 * cl[idx[cut]].weight < target) acc += cl[idx[cut++]].weight;
  // Both halves get at least one cluster when there are enough to go round.
  if (idx.size() >= 2) cut = std::clamp<std::size_t>(cut, 1, idx.size() - 1);
  std::vector<int> lo(idx.begin(), idx.begin() + cut), hi(idx.begin() + cut, idx.end());
  assign_regions(cl, std::move(lo), first, left);
  assign_regions(cl, std::move(hi), first + left, count - left);
}

// assign_regions with measured work, one weight per level (and one for the
// facets): each cut, on whichever axis of the centres does best, minimises
// the sum over levels of the busier half's work per PE, which is what the
// level-by-level occupancy pays for (the busiest PE of each level).
void assign_regions_measured(std::vector<ClusterBuild>& cl, std::vector<int> idx, int first, int count) {
  if (idx.empty()) return;
  if (count == 1) {
    for (int i : idx) cl[i].pe = first;
    return;
  }
  const int left = count / 2, right = count - left;
  const std::size_t D = cl[idx[0]].work.size(), n = idx.size();
  std::vector<double> total(D, 0.0);
  for (int i : idx)
    for (std::size_t d = 0; d < D; ++d) total[d] += cl[i].work[d];
  double best = INFINITY;
  std::vector<int> best_order = idx;
  std::size_t best_cut = n;  // one cluster: all of it goes left
  for (int axis = 0; axis < 3 && n >= 2; ++axis) {
    std::vector<int> order = idx;
    std::sort(order.begin(), order.end(), [&](int a, int b) {
      return cl[a].c[axis] < cl[b].c[axis] || (cl[a].c[axis] == cl[b].c[axis] && a < b);
    });
    std::vector<double> acc(D, 0.0);
    for (std::size_t cut = 1; cut < n; ++cut) {
      double score = 0;
      for (std::size_t d = 0; d < D; ++d) {
        acc[d] += cl[order[cut - 1]].work[d];
        score += std::max(acc[d] / left, (total[d] - acc[d]) / right);
      }
      if (score < best) best = score, best_cut = cut, best_order = order;
    }
  }
  std::vector<int> lo(best_order.begin(), best_order.begin() + best_cut), hi(best_order.begin() + best_cut, best_order.end());
  assign_regions_measured(cl, std::move(lo), first, left);
  assign_regions_measured(cl, std::move(hi), first + left, right);
}

// Sampled rays whose segment crosses box b (slab test over [0, t_max]).
std::uint64_t crossings(const Box& b, const RaySample& sample) {
  std::uint64_t n = 0;
  for (const RaySegment& r : sample.rays) n += slab_test(b, r.origin, r.direction, 0.0f, r.t_max);
  return n;
}

// Each cluster's share of the expected work. Without a ray sample or
// measured work: its share of the facets (banks of equal size).
//
// With a ray sample: mostly its share of the sampled rays that cross its
// box, so that the PEs whose clusters the frame's rays cross most (the floor
// under the camera, the space between lit surfaces and the lights) hold
// fewer of them; a tenth of the weight stays with the facets, so that
// clusters no ray crosses still spread out (a bank holds at most about ten
// times the mean).
//
// With measured work (a pilot frame's tests per facet and level): the
// cluster's tests level by level, and a tenth of the weight on its facets
// (cluster.work, for assign_regions_measured).
//
// Either way, a cluster hotter than half a PE's share (crossed by that many
// sampled rays, or measured that busy) is cut in two first, until it is not
// or cannot be: one hot piece of floor would otherwise set the busiest PE's
// load by itself. Measured in docs/BENCHMARKS.md.
constexpr double kFacetShare = 0.1;

std::vector<std::int64_t> measured_sums(const MeasuredWork& m, const std::vector<int>& tris) {
  std::vector<std::int64_t> w(std::size_t(m.levels), 0);
  for (int t : tris)
    for (int l = 0; l < m.levels; ++l)
      w[std::size_t(l)] += std::llround(
          std::ldexp(double(m.per_facet[std::size_t(t) * std::size_t(m.levels) + std::size_t(l)]), kWorkFractionBits));
  return w;
}

double sampled_weight(std::size_t facets, std::size_t total_facets, std::int64_t heat, std::int64_t all) {
  return kFacetShare * double(facets) / std::max(double(total_facets), 1.0) +
         (1.0 - kFacetShare) * double(heat) / double(all);
}

std::int64_t heat_of(const std::int64_t* sums, int levels) {
  return std::accumulate(sums, sums + levels, std::int64_t(0));
}

bool too_hot(std::int64_t heat, std::int64_t all, int num_pes) {
  return double(heat) > double(all) / (2.0 * num_pes);
}

std::vector<double> measured_weights(const std::int64_t* sums, int levels, std::int64_t all, std::size_t facets,
                                     std::size_t total_facets) {
  std::vector<double> w(std::size_t(levels) + 1);
  for (int l = 0; l < levels; ++l) w[std::size_t(l)] = std::ldexp(double(sums[l]), -kWorkFractionBits);
  w[std::size_t(levels)] = kFacetShare * std::ldexp(double(all), -kWorkFractionBits) * double(facets) /
                           std::max(double(total_facets), 1.0);
  return w;
}

void region_weights(const Scene& scene, std::vector<ClusterBuild>& cb, const RaySample* sample,
                    const MeasuredWork* measured, int num_pes) {
  if (measured && measured->empty()) measured = nullptr;
  if (sample && sample->rays.empty()) sample = nullptr;
  const auto heat_of_cluster = [&](const ClusterBuild& c) -> std::int64_t {
    if (measured) return heat_of(measured_sums(*measured, c.tris).data(), measured->levels);
    return sample ? std::int64_t(crossings(c.box, *sample)) : 0;
  };
  std::vector<std::int64_t> heat(cb.size(), 0);
  std::int64_t all = 0;  // exact: the order of the cuts does not change it
  if (sample || measured) {
    for (std::size_t i = 0; i < cb.size(); ++i) all += heat[i] = heat_of_cluster(cb[i]);
    for (bool cut = all > 0; cut;) {
      cut = false;
      const std::int64_t pass_all = all;  // the limit holds for the whole pass
      for (std::size_t i = 0, n = cb.size(); i < n; ++i) {
        if (!too_hot(heat[i], pass_all, num_pes)) continue;
        Box unused, cbox;
        bounds_of(scene, cb[i].tris, unused, cbox);
        std::vector<int> lower = cb[i].tris, upper;
        if (!cut_at_median(scene, lower, cbox, upper)) continue;
        for (std::vector<int>* half : {&lower, &upper}) {
          Box box, ignored;
          bounds_of(scene, *half, box, ignored);
          ClusterBuild piece = make_cluster(std::move(*half), box);
          const std::int64_t h = heat_of_cluster(piece);
          all += h;
          if (half == &lower) {
            all -= heat[i];
            heat[i] = h;
            cb[i] = std::move(piece);
          } else {
            heat.push_back(h);
            cb.push_back(std::move(piece));
          }
        }
        cut = true;
      }
    }
  }
  std::size_t facets = 0;
  for (const ClusterBuild& c : cb) facets += c.tris.size();
  if (!(all > 0)) {  // facets alone (nothing measured or sampled, or nothing crosses a cluster)
    for (ClusterBuild& c : cb) c.weight = double(c.tris.size());
    return;
  }
  for (std::size_t i = 0; i < cb.size(); ++i) {
    if (measured)
      cb[i].work = measured_weights(measured_sums(*measured, cb[i].tris).data(), measured->levels, all,
                                    cb[i].tris.size(), facets);
    cb[i].weight = sampled_weight(cb[i].tris.size(), facets, heat[i], all);
  }
}

// 1-2. Clusters and regions. Target: several clusters per PE so that
// bisection can balance; regions are about diag / cbrt(P) across. The
// clusters come back sorted by PE.
std::vector<ClusterBuild> form_clusters(const Scene& scene, const Box& sbox, int num_pes, bool split_flat,
                                        const RaySample* sample, const MeasuredWork* measured) {
  std::vector<ClusterBuild> cb = split_clusters(scene, scene.triangles.size(), sbox, num_pes, split_flat);
  region_weights(scene, cb, sample, measured, num_pes);
  std::vector<int> all(cb.size());
  std::iota(all.begin(), all.end(), 0);
  if (!cb.empty() && !cb[0].work.empty())
    assign_regions_measured(cb, all, 0, num_pes);
  else
    assign_regions(cb, all, 0, num_pes);
  std::stable_sort(cb.begin(), cb.end(), [](const ClusterBuild& a, const ClusterBuild& b) { return a.pe < b.pe; });
  return cb;
}

}  // namespace partition_steps
}  // namespace opsila
