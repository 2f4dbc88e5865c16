#include "partition/bank_bvh.h"

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numeric>
#include <string>

#include "core/parallel.h"
#include "core/stage_clock.h"
#include "partition/permute.h"
#include "scene/scene.h"

namespace opsila {

namespace {

constexpr int kWidth = OPSILA_BVH_WIDTH;
constexpr int kFacetsPerLeaf = 4;  // tested in vector lanes (kernels/lib/bvh.cl); 2 and 8 measured (docs/BENCHMARKS.md)
constexpr int kSahDepth = 40;                        // deeper than this, median splits keep the tree shallow
constexpr int kMaxBinaryDepth = OPSILA_BVH_STACK - 8;  // a leaf takes the rest beyond this depth

// Binary tree first; the wide tree is collapsed from it.
struct BinNode {
  Box box;
  int kid[2] = {-1, -1};  // inner: both >= 0
  int first = 0, count = 0;  // leaf: positions [first, first + count) of the item order
  int height = 0;            // 0 for a leaf
  bool keep = false;         // a cluster root: stays a wide node of its own
  std::int16_t slots = 0;    // inner: what slots_of counts, kept from its build
};

// The slots node k takes in a wide node opened down to its leaves and kept
// nodes (one each), up to kWidth + 1; an inner node's, made as it is built.
int slots_of(const std::vector<BinNode>& bin, int k) {
  return bin[k].kid[0] < 0 || bin[k].keep ? 1 : bin[k].slots;
}

class Builder {
  typedef float F4 __attribute__((vector_size(16)));
  typedef int I4 __attribute__((vector_size(16)));
  // A box's lo and hi in lanes 0-2 (no read passes the box's end).
  static void load(const Box& b, F4& lo, F4& hi) {
    static_assert(sizeof(Box) == 6 * sizeof(float), "Box: lo then hi, packed");
    std::memcpy(&lo, &b.lo[0], sizeof lo);  // lane 3: hi[0], unused
    F4 tail;                                 // lo[2], hi[0], hi[1], hi[2]
    std::memcpy(&tail, &b.lo[2], sizeof tail);
    hi = F4{tail[1], tail[2], tail[3], tail[0]};
  }
  // Box::grow lane by lane: std::min(lo, b) is (b < lo ? b : lo) and
  // std::max(hi, b) is (hi < b ? b : hi), so the same bits.
  static void grow(F4& lo, F4& hi, F4 blo, F4 bhi) {
    lo = blo < lo ? blo : lo;
    hi = hi < bhi ? bhi : hi;
  }
  // Items' box and centre box, grown item by item in the items' order.
  struct Bounds {
    F4 lo, hi, clo, chi;
    static Bounds empty() {
      Bounds b;
      b.lo = b.clo = F4{INFINITY, INFINITY, INFINITY, INFINITY};
      b.hi = b.chi = -b.lo;
      return b;
    }
    void grow(F4 blo, F4 bhi) {
      Builder::grow(lo, hi, blo, bhi);
      const F4 c = 0.5f * (blo + bhi);  // Box::center's expression
      Builder::grow(clo, chi, c, c);
    }
    void grow(const Box& b) {
      F4 blo, bhi;
      load(b, blo, bhi);
      grow(blo, bhi);
    }
    void get(Box& box, Box& cbox) const {
      for (int a = 0; a < 3; ++a) box.lo[a] = lo[a], box.hi[a] = hi[a], cbox.lo[a] = clo[a], cbox.hi[a] = chi[a];
    }
  };

 public:
  std::vector<BinNode> bin;

  // Binned SAH over items order[begin, end) (boxes and weights by item id;
  // null weights weigh 1 each), reordering them; leaves of at most
  // leaf_size items. `single` (when not null) turns a one-item leaf into an
  // existing binary node (a cluster's facet tree). `known` (when not null): the items' bounds, found by the
  // parent's split. Returns the node.
  int build(std::vector<int>& order, int begin, int end, const Box* boxes, const float* weight, int leaf_size,
            int depth, const std::vector<int>* single, const Bounds* known = nullptr) {
    if (end - begin == 1 && single) return (*single)[order[begin]];
    int node = static_cast<int>(bin.size());
    bin.emplace_back();
    // The node's box and its items' centre box, in one pass over the items.
    Bounds bounds;
    if (known) {
      bounds = *known;
    } else {
      bounds = Bounds::empty();
      for (int i = begin; i < end; ++i) bounds.grow(boxes[order[i]]);
    }
    Box box, cbox;
    bounds.get(box, cbox);
    bin[node].box = box;
    if ((end - begin <= leaf_size && !single) || (depth >= kMaxBinaryDepth && !single)) {
      bin[node].first = begin;
      bin[node].count = end - begin;
      return node;
    }
    Bounds halves[2];
    bool found = false;
    int mid = split(order, begin, end, boxes, weight, depth, cbox, halves, found);
    int l = build(order, begin, mid, boxes, weight, leaf_size, depth + 1, single, found ? &halves[0] : nullptr);
    int r = build(order, mid, end, boxes, weight, leaf_size, depth + 1, single, found ? &halves[1] : nullptr);
    bin[node].kid[0] = l;
    bin[node].kid[1] = r;
    bin[node].height = 1 + std::max(bin[l].height, bin[r].height);
    bin[node].slots = static_cast<std::int16_t>(std::min(slots_of(bin, l) + slots_of(bin, r), kWidth + 1));
    return node;
  }

 private:
  std::vector<int> scratch_;  // the right side of a partition, reused
  static float center(const Box& b, int a) { return 0.5f * (b.lo[a] + b.hi[a]); }

  // Best binned-SAH plane over the three axes; the median of the longest
  // centroid axis when SAH finds none (equal centres) or the tree is deep.
  // One pass bins every item on all three axes (each box is read once, and
  // a bin is a multiply, not a divide: this is most of a scene's build);
  // a node of n < 16 items gets n bins (most nodes are small, and a bin per
  // item already separates every centre the planes can). A box is handled
  // as two 4-lane vectors (lanes 0-2 the axes): the centres, bin numbers and
  // each bin's min and max are the scalar operations lane by lane, so the
  // same bits, in a third of the instructions.
  static constexpr int kBins = 16;
  struct Bin {  // no initialisers: a node clears only the bins it uses
    F4 lo, hi;
    double w;
    static Bin empty() {
      Bin b;
      b.lo = F4{INFINITY, INFINITY, INFINITY, INFINITY};
      b.hi = -b.lo;
      b.w = 0;
      return b;
    }
    void grow(F4 blo, F4 bhi, double bw) {
      Builder::grow(lo, hi, blo, bhi);
      w += bw;
    }
    void grow(const Bin& b) { grow(b.lo, b.hi, b.w); }
    bool is_empty() const { return !(lo[0] <= hi[0]); }  // no item binned
    float area() const {  // Box::area's expression, the three products side by side
      if (is_empty()) return 0.0f;
      const F4 e = hi - lo, p = e * F4{e[1], e[2], e[0], 0};  // x*y, y*z, z*x
      return 2 * (p[0] + p[1] + p[2]);
    }
  };
  static int bin_of(float c, float lo, float scale, int bins) {
    return std::clamp(static_cast<int>((c - lo) * scale), 0, bins - 1);
  }

  // The lowest-cost plane (axis, and first bin of the right side), or
  // best_axis -1 when none leaves weight on both sides.
  static void best_plane(const std::vector<int>& order, int begin, int end, const Box* boxes, const float* weight,
                         const Box& cbox, int nb, const float* scale, int& best_axis, int& best_bin) {
    Bin bins[3][kBins];
    for (int axis = 0; axis < 3; ++axis)
      for (int k = 0; k < nb; ++k) bins[axis][k] = Bin::empty();
    const F4 clo = {cbox.lo[0], cbox.lo[1], cbox.lo[2], 0.0f}, sc = {scale[0], scale[1], scale[2], 0.0f};
    for (int i = begin; i < end; ++i) {
      F4 lo, hi;
      load(boxes[order[i]], lo, hi);
      const double w = weight ? weight[order[i]] : 1.0;
      I4 k = __builtin_convertvector((0.5f * (lo + hi) - clo) * sc, I4);  // truncated, as static_cast<int>
      k = k < 0 ? 0 : k;
      k = k > nb - 1 ? nb - 1 : k;
      for (int axis = 0; axis < 3; ++axis) bins[axis][k[axis]].grow(lo, hi, w);
    }
    float best_cost = INFINITY;
    for (int axis = 0; axis < 3; ++axis) {
      if (!(cbox.extent(axis) > 0)) continue;
      // The right sides' areas and weights only (whole bins stored and read
      // back were most of a small node's time), grown as before: bin k grown
      // by the side beyond it. An empty bin changes neither side (the same
      // bits), so the plane after one costs what the plane before did and
      // never wins (a small node's bins, one per item, are a third empty).
      float right_area[kBins];
      double right_w[kBins];
      Bin right = Bin::empty();
      for (int k = nb - 1; k > 0; --k) {
        if (!bins[axis][k].is_empty()) {
          Bin wider = bins[axis][k];
          wider.grow(right);
          right = wider;
        }
        right_area[k] = right.area(), right_w[k] = right.w;
      }
      Bin left = Bin::empty();
      for (int s = 1; s < nb; ++s) {
        if (bins[axis][s - 1].is_empty()) continue;
        left.grow(bins[axis][s - 1]);
        if (left.w == 0 || right_w[s] == 0) continue;
        float cost = static_cast<float>(left.area() * left.w + right_area[s] * right_w[s]);
        if (cost < best_cost) best_cost = cost, best_axis = axis, best_bin = s;
      }
    }
  }

  // Splits order[begin, end) and returns where the right half starts; on a
  // SAH plane also each half's bounds, found in the same pass (found).
  int split(std::vector<int>& order, int begin, int end, const Box* boxes, const float* weight, int depth,
            const Box& cbox, Bounds (&halves)[2], bool& found) {
    int best_axis = -1, best_bin = -1;
    const int nb = std::clamp(end - begin, 2, kBins);
    float scale[3];
    for (int axis = 0; axis < 3; ++axis) {
      const float ext = cbox.extent(axis);
      scale[axis] = ext > 0 ? nb / ext : 0.0f;
    }
    if (depth < kSahDepth) best_plane(order, begin, end, boxes, weight, cbox, nb, scale, best_axis, best_bin);
    if (best_axis >= 0) {
      const float lo = cbox.lo[best_axis], sc = scale[best_axis];
      // Stable, so the layout does not depend on the sort implementation
      // (as std::stable_partition, without its allocation at every node).
      int m = begin;
      scratch_.clear();
      halves[0] = halves[1] = Bounds::empty();
      for (int i = begin; i < end; ++i) {
        const int id = order[i];
        F4 blo, bhi;
        load(boxes[id], blo, bhi);
        if (bin_of(center(boxes[id], best_axis), lo, sc, nb) < best_bin) {
          order[m++] = id;
          halves[0].grow(blo, bhi);
        } else {
          scratch_.push_back(id);
          halves[1].grow(blo, bhi);
        }
      }
      std::copy(scratch_.begin(), scratch_.end(), order.begin() + m);
      found = m > begin && m < end;
      if (found) return m;
    }
    int axis = cbox.longest();
    std::stable_sort(order.begin() + begin, order.begin() + end, [&](int a, int b) {
      return boxes[a].center(axis) < boxes[b].center(axis);
    });
    return begin + (end - begin) / 2;
  }
};

// Which of a wide node's n children (binary nodes, the node itself being b)
// to open next, or -1: first the one whose whole subtree fits the slots
// left (the smallest such), since it then needs no wide node of its own
// (opening by area alone left 4 slots of 8 unused on average, measured on
// terrains: more nodes to store and to fetch); else the largest by area.
int child_to_open(const std::vector<BinNode>& bin, const int* kid, int n, int b) {
  const int room = kWidth - n + 1;  // slots an opened child may take
  int pick = -1, pick_slots = room + 1;
  for (int i = 0; i < n; ++i) {
    const BinNode& c = bin[kid[i]];
    if (c.kid[0] < 0 || c.keep || kid[i] == b) continue;
    const int slots = slots_of(bin, kid[i]);  // above room: too many, whatever the count
    if (slots <= room && slots < pick_slots) pick = i, pick_slots = slots;
  }
  if (pick >= 0) return pick;
  for (int i = 0; i < n; ++i) {
    const BinNode& c = bin[kid[i]];
    if (c.kid[0] < 0 || c.keep || kid[i] == b) continue;
    if (pick < 0 || c.box.area() > bin[kid[pick]].box.area()) pick = i;
  }
  return pick;
}

// Collapses binary node b into the wide node nodes[slot] (wide_of[b] =
// slot). `budget` bounds the private stack this subtree may need: a node
// with k children needs k entries, plus what its deepest inner child needs
// beyond the slot it was popped from. A binary chain of height h needs h + 1,
// so a child is opened only while budget - k still covers every remaining
// child's height. Kept nodes (cluster roots) always get a wide node of their
// own, even when they are a single leaf. leaf_child maps a leaf's first
// position to the value stored in BankNode::child. Returns the wide depth.
int collapse(const std::vector<BinNode>& bin, int b, int budget, BankArray<BankNode>& nodes, int slot,
             const std::vector<int>& leaf_child, std::vector<int>& wide_of) {
  wide_of[b] = slot;
  struct Kids {  // at most kWidth, kept on the stack (this runs once per wide node)
    int id[kWidth];
    int n = 0;
    int size() const { return n; }
  } kids;
  if (bin[b].kid[0] < 0) {
    kids.id[kids.n++] = b;
  } else {
    kids.id[kids.n++] = bin[b].kid[0];
    kids.id[kids.n++] = bin[b].kid[1];
  }
  auto own_node = [&](int k) { return k != b && (bin[k].kid[0] >= 0 || bin[k].keep); };
  auto fits = [&](const Kids& set) {
    int h = 0;
    for (int i = 0; i < set.n; ++i) h = std::max(h, bin[set.id[i]].height);
    return set.n <= budget - h;
  };
  while (kids.size() < kWidth) {
    const int pick = child_to_open(bin, kids.id, kids.n, b);
    if (pick < 0) break;
    Kids trial = kids;
    const int opened = trial.id[pick];
    for (int i = trial.n; i > pick + 1; --i) trial.id[i] = trial.id[i - 1];
    trial.id[pick] = bin[opened].kid[0];
    trial.id[pick + 1] = bin[opened].kid[1];
    ++trial.n;
    if (!fits(trial)) break;
    kids = trial;
  }
  const int k = kids.size();
  BankNode wide = empty_node();
  for (int i = 0; i < k; ++i) {
    const BinNode& n = bin[kids.id[i]];
    wide.lo_x[i] = n.box.lo[0], wide.lo_y[i] = n.box.lo[1], wide.lo_z[i] = n.box.lo[2];
    wide.hi_x[i] = n.box.hi[0], wide.hi_y[i] = n.box.hi[1], wide.hi_z[i] = n.box.hi[2];
    if (!own_node(kids.id[i])) {
      wide.child[i] = leaf_child[n.first];
      wide.count[i] = n.count;
    }
  }
  nodes[slot] = wide;
  int depth = 1;
  for (int i = 0; i < k; ++i) {
    if (!own_node(kids.id[i])) continue;
    int child = static_cast<int>(nodes.size());
    nodes.emplace_back();
    nodes[slot].child[i] = child;
    nodes[slot].count[i] = 0;
    depth = std::max(depth, 1 + collapse(bin, kids.id[i], budget - k + 1, nodes, child, leaf_child, wide_of));
  }
  return depth;
}

// Private-stack entries the traversal of nodes[n] can need at most.
int stack_need(const BankArray<BankNode>& nodes, int n) {
  int k = 0, deeper = 0;
  for (int i = 0; i < kWidth; ++i) {
    if (nodes[n].count[i] < 0) continue;
    ++k;
    if (nodes[n].count[i] == 0) deeper = std::max(deeper, stack_need(nodes, nodes[n].child[i]));
  }
  return std::max(k, k - 1 + deeper);
}

void check_stack(const BankArray<BankNode>& nodes, int root) {
  if (stack_need(nodes, root) > OPSILA_BVH_STACK)
    throw InputError("the scene's bounding-volume hierarchy is deeper than the kernels' traversal stack (" +
                     std::to_string(OPSILA_BVH_STACK) + " entries)");
}

}  // namespace

// Inverted boxes for the empty slots (bank_bvh.h).
BankNode empty_node() {
  BankNode n;
  const float inf = std::numeric_limits<float>::infinity();
  for (int i = 0; i < kWidth; ++i) {
    n.lo_x[i] = n.lo_y[i] = n.lo_z[i] = inf;
    n.hi_x[i] = n.hi_y[i] = n.hi_z[i] = -inf;
    n.child[i] = 0;
    n.count[i] = -1;
  }
  return n;
}

int build_bank_bvh(BankArray<BankNode>& nodes, BankArray<BankTriangle>& tris, std::vector<Cluster>& clusters,
                   int c_begin, int c_end, const std::vector<std::pair<int, int>>& ranges,
                   const FacetFollowers& follow) {
  if (c_begin == c_end) return 0;
  // Everything below is the bank's own: positions and cluster numbers count
  // from its first facet and first cluster (banks build side by side).
  const int t_begin = ranges[c_begin].first, t_end = ranges[c_end - 1].second;
  const int nt = t_end - t_begin, nc = c_end - c_begin;
  // The facets' boxes, this bank's only: a scene-wide array of them would
  // be 24 bytes a facet at the preparation's peak.
  std::vector<Box> bank_boxes(static_cast<std::size_t>(nt));
  for (int i = 0; i < nt; ++i) {
    const BankTriangle& t = tris[std::size_t(t_begin + i)];
    bank_boxes[std::size_t(i)].grow(t.v0);
    bank_boxes[std::size_t(i)].grow(t.v1);
    bank_boxes[std::size_t(i)].grow(t.v2);
  }
  const Box* boxes = bank_boxes.data();
  Builder b;
  b.bin.reserve(2 * static_cast<std::size_t>(nt) + static_cast<std::size_t>(nc));  // at most 2 nt - 1 facet nodes
  // Facets: one binary tree per cluster, over positions of the bank's order.
  std::vector<int> order(static_cast<std::size_t>(nt));
  std::iota(order.begin(), order.end(), 0);
  std::vector<int> cluster_root(static_cast<std::size_t>(nc), -1);
  for (int c = 0; c < nc; ++c) {
    const std::pair<int, int>& r = ranges[c_begin + c];
    cluster_root[c] = b.build(order, r.first - t_begin, r.second - t_begin, boxes, nullptr, kFacetsPerLeaf, 1,
                              nullptr);
    b.bin[cluster_root[c]].keep = true;
  }
  // Clusters above them, weighted by their facet counts.
  std::vector<Box> cboxes(static_cast<std::size_t>(nc));
  std::vector<float> cweight(static_cast<std::size_t>(nc), 0.0f);
  std::vector<int> corder(static_cast<std::size_t>(nc));
  std::iota(corder.begin(), corder.end(), 0);
  for (int c = 0; c < nc; ++c) {
    cboxes[c].grow(clusters[c_begin + c].bmin);
    cboxes[c].grow(clusters[c_begin + c].bmax);
    cweight[c] = static_cast<float>(ranges[c_begin + c].second - ranges[c_begin + c].first);
  }
  int root = b.build(corder, 0, nc, cboxes.data(), cweight.data(), 1, 1, &cluster_root);

  // Facets in their new order; leaves name global facet indices.
  std::vector<Box>().swap(bank_boxes);
  permute_bank_facets(order, tris.data() + t_begin, follow, std::size_t(t_begin));
  std::vector<int> leaf_child(static_cast<std::size_t>(nt));
  std::iota(leaf_child.begin(), leaf_child.end(), t_begin);

  int slot = static_cast<int>(nodes.size());
  // Room for the wide nodes up front (a bank's tree measured 1 wide node to
  // 6-8 binary ones): growing by doubling copied and faulted them in again.
  nodes.reserve(nodes.size() + b.bin.size() / 4 + static_cast<std::size_t>(nc) + 1);
  nodes.emplace_back();
  std::vector<int> wide_of(b.bin.size(), -1);
  int depth = collapse(b.bin, root, OPSILA_BVH_STACK, nodes, slot, leaf_child, wide_of);
  for (int c = 0; c < nc; ++c) clusters[c_begin + c].root = wide_of[cluster_root[c]];
  check_stack(nodes, slot);
  return depth;
}

std::vector<BankBvh> build_bank_bvhs(BankArray<BankNode>& nodes, BankArray<BankTriangle>& tris,
                                     std::vector<Cluster>& clusters,
                                     const std::vector<std::pair<int, int>>& pe_clusters,
                                     const std::vector<std::pair<int, int>>& ranges, const FacetFollowers& follow) {
  const std::size_t P = pe_clusters.size();
  StageClock clock(PrepareStage::bank_build);
  std::vector<BankArray<BankNode>> own(P);
  std::vector<BankBvh> out(P);
  std::atomic<std::size_t> done{0};
  // Each task touches only its bank's facets, boxes, sources and clusters.
  // A bank's build holds about 90 bytes of scratch a facet: at most a
  // quarter of the banks at once keeps that under 25 bytes a facet of the
  // process's (a rank of 4 banks on 2 threads held half its share's worth).
  const int at_once = std::clamp(int(P) / 4, 1, host_threads());
  const auto build = [&](std::size_t p) {
    out[p].depth =
        build_bank_bvh(own[p], tris, clusters, pe_clusters[p].first, pe_clusters[p].second, ranges, follow);
    clock.progress(double(++done) / double(P));
  };
  parallel_for(P, build, at_once);
  // In PE order, as one build after another would have laid them out.
  std::size_t total = nodes.size();
  for (const BankArray<BankNode>& v : own) total += v.size();
  nodes.reserve(total);
  for (std::size_t p = 0; p < P; ++p) {
    const int base = static_cast<int>(nodes.size());
    out[p].node_begin = base;
    for (BankNode& n : own[p]) {
      for (int i = 0; i < kWidth; ++i)
        if (n.count[i] == 0) n.child[i] += base;
      nodes.push_back(n);
    }
    BankArray<BankNode>().swap(own[p]);
    out[p].node_end = static_cast<int>(nodes.size());
    for (int c = pe_clusters[p].first; c < pe_clusters[p].second; ++c) clusters[c].root += base;
  }
  return out;
}

void build_route_bvh(BankArray<BankNode>& nodes, int root, const std::vector<Box>& boxes,
                     const std::vector<int>& cluster_ids) {
  nodes[root] = empty_node();
  if (boxes.empty()) return;
  Builder b;
  std::vector<int> order(boxes.size());
  std::iota(order.begin(), order.end(), 0);
  int top = b.build(order, 0, static_cast<int>(boxes.size()), boxes.data(), nullptr, 1, 1, nullptr);
  std::vector<int> leaf_child(boxes.size());
  for (std::size_t i = 0; i < boxes.size(); ++i) leaf_child[i] = cluster_ids[order[i]];
  std::vector<int> wide_of(b.bin.size(), -1);
  collapse(b.bin, top, OPSILA_BVH_STACK, nodes, root, leaf_child, wide_of);
  check_stack(nodes, root);
}

bool children_box(const BankNode &node, Box &box) {
  box = Box{};
  bool any = false;
  for (int k = 0; k < OPSILA_BVH_WIDTH; ++k) {
    if (node.count[k] < 0) continue;
    const float lo[3] = {node.lo_x[k], node.lo_y[k], node.lo_z[k]};
    const float hi[3] = {node.hi_x[k], node.hi_y[k], node.hi_z[k]};
    box.grow(lo);
    box.grow(hi);
    any = true;
  }
  return any;
}

}  // namespace opsila
