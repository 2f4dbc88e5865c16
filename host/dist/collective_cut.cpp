#include "dist/collective_cut.h"

#include <algorithm>
#include <cstring>
#include <utility>

#include "core/errors.h"

namespace opsila {

using namespace partition_steps;

namespace {

// A float's bits as an unsigned integer in the floats' order (-0 just
// below +0): integer max over the ranks is then exact float max.
std::uint32_t ordered_bits(float f) {
  std::uint32_t b;
  std::memcpy(&b, &f, sizeof b);
  return (b & 0x80000000u) ? ~b : (b | 0x80000000u);
}

float from_ordered(std::uint32_t o) {
  const std::uint32_t b = (o & 0x80000000u) ? (o & 0x7fffffffu) : ~o;
  float f;
  std::memcpy(&f, &b, sizeof f);
  return f;
}

// Boxes joined over the ranks: the highest of every hi, and of every lo
// complemented (so the lowest lo). A rank's empty box (lo +inf, hi -inf)
// changes nothing.
void join_boxes(std::vector<Box*> boxes, Ranks& ranks) {
  std::vector<std::uint64_t> v;
  for (const Box* b : boxes)
    for (int a = 0; a < 3; ++a) v.push_back(0xffffffffu - ordered_bits(b->lo[a])), v.push_back(ordered_bits(b->hi[a]));
  ranks.max(v);
  std::size_t k = 0;
  for (Box* b : boxes)
    for (int a = 0; a < 3; ++a) {
      b->lo[a] = from_ordered(static_cast<std::uint32_t>(0xffffffffu - v[k++]));
      b->hi[a] = from_ordered(static_cast<std::uint32_t>(v[k++]));
    }
}

// split_object's recursion on an object spread over the ranks, every rank
// in step: the same boxes, counts and decisions everywhere, each rank
// cutting its own facets at the key every rank agreed on.
void split_spread(const Scene& share, std::vector<int> cur, const SplitLimits& limits, bool split_flat, int object,
                  ShareClusters& out, Ranks& ranks, const std::function<void(double)>& progress) {
  Box box, cbox;
  spread_bounds(share, cur, box, cbox, ranks);
  const std::uint64_t n = ranks.sum(cur.size());
  std::vector<int> upper;
  if (!needs_cut(n, box, limits, split_flat) || !cut_spread_at_median(share, cur, cbox, n, upper, ranks)) {
    out.spread.push_back({static_cast<int>(out.clusters.size()), object, n});
    out.clusters.push_back(make_cluster(std::move(cur), box));
    out.spread_done += n;
    if (progress) progress(double(out.spread_done) / double(std::max<std::size_t>(share.total_triangles(), 1)));
    return;
  }
  split_spread(share, std::move(upper), limits, split_flat, object, out, ranks, progress);
  split_spread(share, std::move(cur), limits, split_flat, object, out, ranks, progress);
}

}  // namespace

std::uint64_t cut_key(float centroid, std::uint32_t order) {
  if (centroid == 0.0f) centroid = 0.0f;  // -0 and +0 compare equal: the order breaks the tie
  return (std::uint64_t(ordered_bits(centroid)) << 32) | order;
}

RadixSelect::RadixSelect(std::vector<std::uint64_t> keys, std::uint64_t k) : candidates_(std::move(keys)), k_(k) {}

std::vector<std::uint64_t> RadixSelect::histogram() const {
  std::vector<std::uint64_t> h(kBuckets, 0);
  for (std::uint64_t key : candidates_) ++h[(key >> shift_) & (kBuckets - 1)];
  return h;
}

void RadixSelect::narrow(const std::vector<std::uint64_t>& summed) {
  std::uint64_t digit = 0;
  while (digit + 1 < kBuckets && k_ >= summed[digit]) k_ -= summed[digit++];
  prefix_ |= digit << shift_;
  const int shift = shift_;
  candidates_.erase(std::remove_if(candidates_.begin(), candidates_.end(),
                                   [&](std::uint64_t key) { return ((key >> shift) & (kBuckets - 1)) != digit; }),
                    candidates_.end());
  shift_ -= kDigitBits;
}

SelectedKey select_key(std::vector<std::uint64_t> keys, std::uint64_t k,
                       const std::function<void(std::vector<std::uint64_t>&)>& sum) {
  RadixSelect select(std::move(keys), k);
  while (!select.done()) {
    std::vector<std::uint64_t> h = select.histogram();
    sum(h);
    select.narrow(h);
  }
  return {select.key(), select.equal_below()};
}

std::vector<char> lower_half(const std::vector<std::uint64_t>& keys, const SelectedKey& at) {
  std::vector<char> below(keys.size(), 0);
  std::uint64_t ties = at.equal_below;
  for (std::size_t i = 0; i < keys.size(); ++i)
    below[i] = keys[i] < at.key || (keys[i] == at.key && ties > 0 && ties--);
  return below;
}

void spread_bounds(const Scene& share, const std::vector<int>& tris, Box& box, Box& cbox, Ranks& ranks) {
  bounds_of(share, tris, box, cbox);
  join_boxes({&box, &cbox}, ranks);
}

bool cut_spread_at_median(const Scene& share, std::vector<int>& tris, const Box& cbox, std::uint64_t n,
                          std::vector<int>& upper, Ranks& ranks) {
  const int axis = cbox.longest();
  if (n < 2 || !(cbox.extent(axis) > 0)) return false;
  std::vector<std::uint64_t> keys(tris.size());
  for (std::size_t i = 0; i < tris.size(); ++i) {
    const Triangle& t = share.triangles[std::size_t(tris[i])];
    keys[i] = cut_key(centroid(t, axis), static_cast<std::uint32_t>(t.facet_id));
  }
  // The median, n / 2 from the bottom: the lower half is the n / 2 keys below it.
  const SelectedKey median = select_key(keys, n / 2, [&](std::vector<std::uint64_t>& h) { ranks.sum(h); });
  const std::vector<char> below = lower_half(keys, median);
  std::vector<int> lower;
  upper.clear();
  for (std::size_t i = 0; i < tris.size(); ++i) (below[i] ? lower : upper).push_back(tris[i]);
  tris = std::move(lower);
  return true;
}

ShareClusters split_share(const Scene& share, const Box& sbox, int num_pes, bool split_flat, Ranks& ranks,
                          const std::function<void(double)>& progress) {
  const SplitLimits limits = split_limits(share.total_triangles(), sbox, num_pes);
  std::vector<std::vector<int>> by_object = triangles_by_object(share);
  std::vector<char> spread(by_object.size(), 0);
  for (int o : share.share.spread) spread.at(std::size_t(o)) = 1;
  ShareClusters out;
  for (std::size_t o = 0; o < by_object.size(); ++o)
    if (!spread[o] && !by_object[o].empty())
      split_object(share, std::move(by_object[o]), limits.max_tris, limits.max_extent, split_flat, out.clusters,
                   split_threads());
  for (int o : share.share.spread)
    split_spread(share, std::move(by_object[std::size_t(o)]), limits, split_flat, o, out, ranks, progress);
  return out;
}

namespace {

// Every rank's record of what it read, compared by the largest and the
// smallest of each value (one collective each, the same on every rank).
void check_same_reads(const SceneShare& share, Ranks& ranks) {
  std::vector<std::uint64_t> high{share.reads.size()};
  for (const auto& [file, figures] : share.reads) high.insert(high.end(), figures.begin(), figures.end());
  std::vector<std::uint64_t> length{high.size()}, low_length{~high.size()};
  ranks.max(length), ranks.max(low_length);
  std::vector<std::uint64_t> low(high.size());
  for (std::size_t k = 0; k < high.size(); ++k) low[k] = ~high[k];
  if (length[0] == ~low_length[0]) ranks.max(high), ranks.max(low);
  std::size_t at = 1;
  for (const auto& [file, figures] : share.reads) {
    bool same = length[0] == ~low_length[0];
    for (std::size_t k = 0; same && k < figures.size(); ++k) same = high[at + k] == ~low[at + k];
    if (!same)
      throw InputError(file + ": the ranks did not read the same file (its size, modification time or contents "
                              "differ between ranks): it changed while they read it, or they see different copies");
    at += figures.size();
  }
  if (length[0] != ~low_length[0]) throw InputError("the ranks did not stream the same model files");
}

}  // namespace

void combine_share(SceneShare& share, Ranks& ranks) {
  ranks.checkpoint();  // a rank that failed reading its share is waiting there
  check_same_reads(share, ranks);
  share.total_triangles = share.total_triangles - share.window_triangles + ranks.sum(share.window_triangles);
  ranks.sum(share.window_dropped);  // as many entries on every rank
  Box b;
  b.lo = share.lo;
  b.hi = share.hi;
  join_boxes({&b}, ranks);
  share.lo = b.lo;
  share.hi = b.hi;
}

}  // namespace opsila
