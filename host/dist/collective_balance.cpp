// --balance measured and work on a scene read in shares: the cluster table
// with each cluster's heat, and region_weights' cuts of the hot clusters,
// by every rank together (dist/collective_balance.h); and the ray sample
// of --balance work, traced by the ranks together. Measured work is summed
// in fixed point (partition_steps::measured_sums), so a spread cluster's
// sum over the ranks is exactly one process's sum over its facets.
#include "dist/collective_balance.h"

#include <algorithm>
#include <numeric>
#include <stdexcept>
#include <type_traits>
#include <utility>

#include "core/stage_clock.h"

namespace opsila {

using namespace partition_steps;

// The same on every rank (a rank's share of the measured work may be
// empty): every rank takes the same collective steps.
int ShareHeat::levels() const {
  if (measured) return measured->levels;
  return sample && !sample->rays.empty() ? 1 : 0;
}

std::vector<std::int64_t> ShareHeat::of(const std::vector<int>& tris, const Box& box) const {
  if (measured) return measured_sums(*measured, tris);
  if (sample && !sample->rays.empty()) return {std::int64_t(crossings(box, *sample))};
  return {};
}

namespace {

// A cluster cut in two, as every rank learns it; its pieces' work follows
// in a second stream (2 x levels sums: the lower piece's, then the upper's).
struct CutRecord {
  std::int32_t parent = 0;  // its index in the table
  ClusterSummary lower, upper;
};

static_assert(std::is_trivially_copyable<ClusterSummary>::value && std::is_trivially_copyable<CutRecord>::value,
              "sent as bytes");

ClusterSummary summary_of(const ClusterBuild& c, const ClusterSummary& like, std::int32_t local,
                          std::uint64_t facets) {
  ClusterSummary s = like;
  s.local = local;
  s.facets = facets;
  for (int a = 0; a < 3; ++a) s.c[a] = c.c[a], s.lo[a] = c.box.lo[a], s.hi[a] = c.box.hi[a];
  return s;
}

// Sums over every rank, in place (non-negative, so sent as unsigned).
void sum_over_ranks(std::vector<std::int64_t>& v, Ranks& ranks) {
  std::vector<std::uint64_t> u(v.begin(), v.end());
  ranks.sum(u);
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = static_cast<std::int64_t>(u[i]);
}

// A cluster this rank holds alone, cut as region_weights cuts it.
bool cut_own(const Scene& share, const ShareHeat& heat, ShareClusters& split, const ClusterSummary& s,
             CutRecord& r, std::vector<std::int64_t>& work) {
  const std::vector<int>& tris = split.clusters[std::size_t(s.local)].tris;
  Box unused, cbox;
  bounds_of(share, tris, unused, cbox);
  std::vector<int> lower = tris, upper;
  if (!cut_at_median(share, lower, cbox, upper)) return false;
  Box lbox, ubox, ignored;
  bounds_of(share, lower, lbox, ignored);
  bounds_of(share, upper, ubox, ignored);
  work = heat.of(lower, lbox);
  const std::vector<std::int64_t> up = heat.of(upper, ubox);
  work.insert(work.end(), up.begin(), up.end());
  ClusterBuild lo = make_cluster(std::move(lower), lbox), hi = make_cluster(std::move(upper), ubox);
  r.lower = summary_of(lo, s, s.local, lo.tris.size());
  r.upper = summary_of(hi, s, static_cast<std::int32_t>(split.clusters.size()), hi.tris.size());
  split.clusters[std::size_t(s.local)] = std::move(lo);
  split.clusters.push_back(std::move(hi));
  return true;
}

// A spread cluster, cut by every rank together: the same decision, the
// same halves, the pieces' boxes and work joined over the ranks.
bool cut_spread(const Scene& share, const ShareHeat& heat, ShareClusters& split, const ClusterSummary& s,
                CutRecord& r, std::vector<std::int64_t>& work, Ranks& ranks) {
  const ShareClusters::Spread sp = split.spread[std::size_t(s.local)];
  std::vector<int> lower = split.clusters[std::size_t(sp.local)].tris, upper;
  Box unused, cbox;
  spread_bounds(share, lower, unused, cbox, ranks);
  if (!cut_spread_at_median(share, lower, cbox, s.facets, upper, ranks)) return false;
  Box lbox, ubox, ignored;
  spread_bounds(share, lower, lbox, ignored, ranks);
  spread_bounds(share, upper, ubox, ignored, ranks);
  work = heat.of(lower, lbox);
  const std::vector<std::int64_t> up = heat.of(upper, ubox);
  work.insert(work.end(), up.begin(), up.end());
  if (heat.summed()) sum_over_ranks(work, ranks);
  const std::uint64_t n_lower = s.facets / 2;  // the median's rank: the lower half is the n / 2 lowest keys
  ClusterBuild lo = make_cluster(std::move(lower), lbox), hi = make_cluster(std::move(upper), ubox);
  r.lower = summary_of(lo, s, s.local, n_lower);
  r.upper = summary_of(hi, s, static_cast<std::int32_t>(split.spread.size()), s.facets - n_lower);
  split.spread[std::size_t(s.local)].facets = n_lower;
  split.spread.push_back({static_cast<int>(split.clusters.size()), sp.object, s.facets - n_lower});
  split.clusters[std::size_t(sp.local)] = std::move(lo);
  split.clusters.push_back(std::move(hi));
  return true;
}

std::int64_t table_heat(const ClusterTable& t, std::size_t k) {
  return heat_of(t.work.data() + k * std::size_t(t.levels), t.levels);
}

// Every rank's cuts of one pass, in the table's order: each lower piece in
// its cluster's place, the upper ones after every cluster. False: none.
bool apply_cuts(ClusterTable& t, const std::vector<CutRecord>& mine, const std::vector<std::int64_t>& mine_work,
                Ranks& ranks) {
  const std::vector<CutRecord> got = records_of<CutRecord>(ranks.all_gather(bytes_of(mine)));
  const std::vector<std::int64_t> work = records_of<std::int64_t>(ranks.all_gather(bytes_of(mine_work)));
  std::vector<std::size_t> order(got.size());
  std::iota(order.begin(), order.end(), std::size_t(0));
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return got[a].parent < got[b].parent; });
  const std::size_t L = std::size_t(t.levels);
  for (std::size_t i : order) {
    const std::size_t k = std::size_t(got[i].parent);
    t.clusters[k] = got[i].lower;
    std::copy_n(work.begin() + std::ptrdiff_t(2 * L * i), L, t.work.begin() + std::ptrdiff_t(k * L));
  }
  for (std::size_t i : order) {
    t.clusters.push_back(got[i].upper);
    const auto upper = work.begin() + std::ptrdiff_t(2 * L * i + L);
    t.work.insert(t.work.end(), upper, upper + std::ptrdiff_t(L));
  }
  return !got.empty();
}

}  // namespace

ClusterTable gather_clusters(const Scene& share, const ShareClusters& split, const ShareHeat& heat, Ranks& ranks) {
  const std::vector<ClusterBuild>& local = split.clusters;
  const std::size_t L = std::size_t(heat.levels());
  std::vector<int> spread_of(local.size(), -1);
  for (std::size_t k = 0; k < split.spread.size(); ++k) spread_of[std::size_t(split.spread[k].local)] = int(k);
  // A spread cluster's work over every rank (each holds part of its facets).
  std::vector<std::int64_t> spread_work;
  for (const ShareClusters::Spread& sp : split.spread) {
    const ClusterBuild& c = local[std::size_t(sp.local)];
    const std::vector<std::int64_t> w = heat.of(c.tris, c.box);
    spread_work.insert(spread_work.end(), w.begin(), w.end());
  }
  if (heat.summed()) sum_over_ranks(spread_work, ranks);
  std::vector<ClusterSummary> mine;
  std::vector<std::int64_t> mine_work;
  const int last_object = std::max(share.num_objects, 1) - 1;
  for (std::size_t i = 0; i < local.size(); ++i) {
    const int k = spread_of[i];
    if (k >= 0 && ranks.rank() != 0) continue;  // the same on every rank: rank 0 alone lists it
    ClusterSummary like;
    like.object = k >= 0 ? split.spread[std::size_t(k)].object
                         : std::clamp(share.triangles[std::size_t(local[i].tris[0])].object_id, 0, last_object);
    like.rank = k >= 0 ? 0 : ranks.rank();
    like.spread = k >= 0 ? 1 : 0;
    mine.push_back(summary_of(local[i], like, k >= 0 ? k : static_cast<int>(i),
                              k >= 0 ? split.spread[std::size_t(k)].facets : local[i].tris.size()));
    const std::vector<std::int64_t> w =
        k >= 0 ? std::vector<std::int64_t>(spread_work.begin() + std::ptrdiff_t(std::size_t(k) * L),
                                           spread_work.begin() + std::ptrdiff_t(std::size_t(k + 1) * L))
               : heat.of(local[i].tris, local[i].box);
    mine_work.insert(mine_work.end(), w.begin(), w.end());
  }
  const std::vector<ClusterSummary> all = records_of<ClusterSummary>(ranks.all_gather(bytes_of(mine)));
  const std::vector<std::int64_t> work = records_of<std::int64_t>(ranks.all_gather(bytes_of(mine_work)));
  std::vector<std::size_t> order(all.size());
  std::iota(order.begin(), order.end(), std::size_t(0));
  std::stable_sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) {
    const ClusterSummary &a = all[x], &b = all[y];
    return a.object < b.object || (a.object == b.object && (a.rank < b.rank || (a.rank == b.rank && a.local < b.local)));
  });
  ClusterTable t;
  t.levels = static_cast<int>(L);
  t.sampled = L > 0 && !heat.summed();
  for (std::size_t i : order) {
    t.clusters.push_back(all[i]);
    t.work.insert(t.work.end(), work.begin() + std::ptrdiff_t(i * L), work.begin() + std::ptrdiff_t((i + 1) * L));
  }
  return t;
}

void cut_hot_clusters(const Scene& share, const ShareHeat& heat, int num_pes, ShareClusters& split,
                      ClusterTable& t, Ranks& ranks) {
  std::int64_t all = 0;
  for (std::size_t k = 0; k < t.clusters.size(); ++k) all += table_heat(t, k);
  for (bool cut = all > 0; cut;) {
    std::vector<CutRecord> mine;
    std::vector<std::int64_t> mine_work;
    for (std::size_t k = 0, n = t.clusters.size(); k < n; ++k) {
      const ClusterSummary s = t.clusters[k];
      if (!too_hot(table_heat(t, k), all, num_pes) || (!s.spread && s.rank != ranks.rank())) continue;
      CutRecord r;
      r.parent = static_cast<std::int32_t>(k);
      std::vector<std::int64_t> work;
      const bool done = s.spread ? cut_spread(share, heat, split, s, r, work, ranks)
                                 : cut_own(share, heat, split, s, r, work);
      if (!done || (s.spread && ranks.rank() != 0)) continue;  // a spread cluster's pieces: rank 0 reports them
      mine.push_back(r);
      mine_work.insert(mine_work.end(), work.begin(), work.end());
    }
    cut = apply_cuts(t, mine, mine_work, ranks);
    all = 0;  // exact, so the same as one process's running total
    for (std::size_t k = 0; k < t.clusters.size(); ++k) all += table_heat(t, k);
  }
}

namespace {

// The sample's joins over the ranks (scene/ray_sample.h).
class RanksJoin : public SampleJoin {
 public:
  explicit RanksJoin(Ranks& ranks) : ranks_(ranks) {}
  int holder() const override { return ranks_.rank(); }
  void min(std::vector<std::uint64_t>& v) const override {
    for (std::uint64_t& x : v) x = ~x;  // the least is the greatest complement
    ranks_.max(v);
    for (std::uint64_t& x : v) x = ~x;
  }
  std::vector<unsigned char> all_gather(const std::vector<unsigned char>& mine) const override {
    return ranks_.all_gather(mine);
  }

 private:
  Ranks& ranks_;
};

}  // namespace

RaySample balance_sample(const Scene& scene, const RaySampler& sampler, Ranks& ranks) {
  if (!sampler) throw std::invalid_argument("--balance work: neither a ray sample nor a sampler");
  const StageClock clock(PrepareStage::partition);  // the sample serves the partition alone
  if (!scene.is_share()) return sampler(scene, nullptr);
  const RanksJoin join(ranks);
  return sampler(scene, &join);
}

}  // namespace opsila
