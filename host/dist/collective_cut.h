// Median cuts of an object whose facets lie on several ranks (a terrain
// made in windows, docs/DISTRIBUTED.md): the same recursion as
// partition_steps::split_object, run by every rank together. Boxes and
// counts are joined over the ranks (MPI_Allreduce min/max/sum, exact), and
// the median is found by a radix select on the facets' keys with integer
// histograms summed over the ranks, so each cut makes exactly the halves
// one process's nth_element makes.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "partition/partition_steps.h"
#include "mpi/ranks.h"

namespace opsila {

// A facet's key for a median cut on one axis: its centroid's float bits
// ordered as the floats are (-0 as +0), then its order among the object's
// facets (the facet id, which grows with one process's triangle index), so
// keys compare as split_object's (centroid, index) pairs do.
std::uint64_t cut_key(float centroid, std::uint32_t order);

// The k-th smallest (from 0) of keys spread over several holders, found a
// digit (8 bits) at a time from the top: each holder counts its remaining
// candidates by their next digit (histogram()), the counts are summed over
// the holders, and narrow() keeps the digit that holds the k-th key.
class RadixSelect {
 public:
  static constexpr int kDigitBits = 8;
  static constexpr int kBuckets = 1 << kDigitBits;
  RadixSelect(std::vector<std::uint64_t> keys, std::uint64_t k);
  bool done() const { return shift_ < 0; }
  std::vector<std::uint64_t> histogram() const;          // this holder's counts of the next digit
  void narrow(const std::vector<std::uint64_t>& summed);  // every holder's counts, added up
  std::uint64_t key() const { return prefix_; }          // once done: the k-th smallest key
  std::uint64_t equal_below() const { return k_; }       // once done: keys equal to it that rank below it

 private:
  std::vector<std::uint64_t> candidates_;  // this holder's keys that share the prefix found so far
  std::uint64_t k_;                        // rank of the sought key among all holders' candidates
  std::uint64_t prefix_ = 0;
  int shift_ = 64 - kDigitBits;
};

// The k-th smallest of every rank's keys, and how many keys equal to it
// rank below it (ties: the triangles of one polygon with the same centroid
// share a facet id); `sum` adds a histogram up over the ranks in place
// (MPI_Allreduce, or a test's simulated ranks).
struct SelectedKey {
  std::uint64_t key = 0;
  std::uint64_t equal_below = 0;
};
SelectedKey select_key(std::vector<std::uint64_t> keys, std::uint64_t k,
                       const std::function<void(std::vector<std::uint64_t>&)>& sum);

// Which of a rank's keys (listed in its triangles' order) fall in the lower
// half of a cut at `at`: those below its key, and the first at.equal_below
// equal to it. Equal keys name one facet, whose triangles one rank holds in
// one process's order, so the halves are nth_element's on (centroid, index).
std::vector<char> lower_half(const std::vector<std::uint64_t>& keys, const SelectedKey& at);

// A piece of a spread object over every rank: its box and its centroids'
// box, joined (collective).
void spread_bounds(const Scene& share, const std::vector<int>& tris, Box& box, Box& cbox, Ranks& ranks);
// cut_at_median on a spread piece, by every rank together: `tris` (this
// rank's facets of it) keeps its part of the lower half, `upper` gets the
// rest; `cbox` and `n` are the piece's over every rank. False (nothing
// moved) when it cannot be cut.
bool cut_spread_at_median(const Scene& share, std::vector<int>& tris, const Box& cbox, std::uint64_t n,
                          std::vector<int>& upper, Ranks& ranks);

// A scene read in shares cut into clusters: each rank's own objects alone
// (split_object), the objects spread over ranks (SceneShare::spread)
// together. A spread object's clusters are made in the same order on every
// rank, each holding this rank's facets of it (maybe none).
struct ShareClusters {
  std::vector<partition_steps::ClusterBuild> clusters;
  struct Spread {
    int local = 0;            // index in `clusters`
    int object = 0;
    std::uint64_t facets = 0;  // on every rank together
  };
  std::vector<Spread> spread;  // in the order every rank made them
  std::uint64_t spread_done = 0;  // facets of the spread objects in clusters so far (every rank's)
};
// `progress` (may be empty) hears the fraction of the scene's facets in
// clusters so far.
ShareClusters split_share(const Scene& share, const Box& sbox, int num_pes, bool split_flat, Ranks& ranks,
                          const std::function<void(double)>& progress);

// The whole scene's figures from every rank's (SceneShare::combine): the
// windowed triangles and their dropped ones added up, the bounds joined. A collective call, made
// when every rank has read its share; a rank that failed before stops them all.
void combine_share(SceneShare& share, Ranks& ranks);

}  // namespace opsila
