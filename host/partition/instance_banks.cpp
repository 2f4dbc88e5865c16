#include "partition/instance_banks.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "core/parallel.h"
#include "partition/bank_bvh.h"
#include "partition/pe_group.h"
#include "partition/partition_steps.h"
#include "scene/instances.h"

namespace opsila {

namespace {

// Instances idx to PEs [first, first + count): halves of the instances
// (in proportion to the PEs on each side) at the median centre on the
// longest axis of their centres, ties by index.
void bisect(const std::vector<Vec3>& centre, std::vector<int> idx, int first, int count, std::vector<int>& pe_of) {
  if (count == 1 || idx.size() <= 1) {
    for (int i : idx) pe_of[std::size_t(i)] = first;
    return;
  }
  Box b;
  for (int i : idx) b.grow(centre[std::size_t(i)]);
  const int axis = b.longest();
  const int left = count / 2;
  const std::size_t cut = idx.size() * std::size_t(left) / std::size_t(count);
  std::nth_element(idx.begin(), idx.begin() + std::ptrdiff_t(cut), idx.end(), [&](int x, int y) {
    const float a = centre[std::size_t(x)][axis], c = centre[std::size_t(y)][axis];
    return a != c ? a < c : x < y;
  });
  std::vector<int> upper(idx.begin() + std::ptrdiff_t(cut), idx.end());
  idx.resize(cut);
  bisect(centre, std::move(idx), first, left, pe_of);
  bisect(centre, std::move(upper), first + left, count - left, pe_of);
}

// A model's facets and BVH, in its frame, as one bank would hold them from
// index 0; `attributes`: each facet's Scene::attributes index (when the
// scene has any), in the tree's facet order.
struct ModelTree {
  BankArray<BankTriangle> tris;
  BankArray<BankNode> nodes;
  std::vector<int> attributes;
};

ModelTree build_model(const Scene& scene, const Prototype& p) {
  ModelTree m;
  m.tris.reserve(p.triangles.size());
  for (const Triangle& t : p.triangles) {
    m.tris.push_back(partition_steps::bank_triangle(t));
    if (!scene.attributes.empty()) m.attributes.push_back(t.attributes);
  }
  std::vector<Cluster> one(1);
  for (int a = 0; a < 3; ++a) one[0].bmin[a] = p.lo[a], one[0].bmax[a] = p.hi[a];
  const std::vector<std::pair<int, int>> range = {{0, static_cast<int>(m.tris.size())}};
  std::vector<int> none;
  build_bank_bvh(m.nodes, m.tris, one, 0, 1, range, {&m.attributes, &none});
  return m;  // its root is node 0, the bank root
}

// Every instance's world box (instance_holding_box), made once for the partition.
std::vector<Box> instance_boxes(const Scene& scene) {
  std::vector<Box> boxes(scene.instances.size());
  parallel_for(boxes.size(), [&](std::size_t i) { instance_holding_box(scene, scene.instances[i], boxes[i].lo, boxes[i].hi); });
  return boxes;
}

// The BVH over one bank's instances (world boxes), its leaves naming them.
BankArray<BankNode> instance_tree(const std::vector<Box>& all, const std::vector<int>& insts) {
  std::vector<Box> boxes(insts.size());
  for (std::size_t k = 0; k < insts.size(); ++k) boxes[k] = all[std::size_t(insts[k])];
  BankArray<BankNode> t(1);
  build_route_bvh(t, 0, boxes, insts);
  for (BankNode& n : t)
    for (int k = 0; k < OPSILA_BVH_WIDTH; ++k)
      if (n.count[k] == 1) n.count[k] = OPSILA_INSTANCE_LEAF;
  return t;
}

// Nodes appended to `out` with their links moved: inner children by
// node_delta, facets by tri_delta (instance leaves keep their index).
void append_nodes(BankArray<BankNode>& out, const BankNode* first, const BankNode* last, int node_delta,
                  int tri_delta) {
  for (const BankNode* n = first; n != last; ++n) {
    BankNode m = *n;
    for (int k = 0; k < OPSILA_BVH_WIDTH; ++k) {
      if (m.count[k] == 0) m.child[k] += node_delta;
      else if (m.count[k] > 0 && m.count[k] != OPSILA_INSTANCE_LEAF) m.child[k] += tri_delta;
    }
    out.push_back(m);
  }
}

Cluster instance_cluster(const Box& b, int i, int pe, const Box& sbox) {
  Cluster cl{};
  for (int a = 0; a < 3; ++a) cl.center[a] = b.center(a), cl.bmin[a] = b.lo[a], cl.bmax[a] = b.hi[a];
  cl.radius = partition_steps::routing_sphere_radius(0.5 * b.diagonal(), cl, sbox);
  cl.pe = pe;
  cl.root = -2 - i;
  return cl;
}

// The new arrays, filled bank by bank.
struct Layout {
  BankArray<BankTriangle> tris;
  BankArray<BankNode> nodes;
  std::vector<Cluster> clusters;
  std::vector<int> attributes;
  std::vector<Box> boxes;  // every instance's (instance_boxes)
  // The models' copies of the device being laid out: root node, -1 none yet.
  int device = -1;
  std::vector<int> copy_root;
};

std::uint64_t model_bytes(const ModelTree& m) {
  return m.tris.size() * sizeof(BankTriangle) + m.nodes.size() * sizeof(BankNode);
}

// PE p's bank (bs.pes[p], its instances `insts` under `tree`) appended to `out`, and
// bs.pes[p] set to its new ranges; a model the device holds no copy of
// yet is copied into it. Returns the bank's bytes (each model it places
// counted, as a texture is); `nodes` gets the nodes among them.
std::uint64_t lay_out_bank(const Scene& scene, const std::vector<ModelTree>& models, const std::vector<int>& insts,
                           const BankArray<BankNode>& tree, const Box& sbox, BankedScene& bs, std::size_t p,
                           const std::vector<int>& attributes, Layout& out, std::uint64_t& nodes) {
  PeInfo& pe = bs.pes[p];
  nodes = std::uint64_t(pe.node_end - pe.node_begin);
  std::uint64_t bytes = std::uint64_t(pe.tri_end - pe.tri_begin) * sizeof(BankTriangle) + nodes * sizeof(BankNode);
  const int tri0 = static_cast<int>(out.tris.size()), node0 = static_cast<int>(out.nodes.size());
  const int t_delta = tri0 - pe.tri_begin, n_delta = node0 - pe.node_begin;
  out.tris.insert(out.tris.end(), bs.triangles.begin() + pe.tri_begin, bs.triangles.begin() + pe.tri_end);
  if (!scene.attributes.empty())  // then one per facet
    out.attributes.insert(out.attributes.end(), attributes.begin() + pe.tri_begin, attributes.begin() + pe.tri_end);
  append_nodes(out.nodes, bs.nodes.data() + pe.node_begin, bs.nodes.data() + pe.node_end, n_delta, t_delta);
  for (int c = pe.cluster_begin; c < pe.cluster_end; ++c) {
    Cluster cl = bs.clusters[std::size_t(c)];
    if (cl.root >= 0) cl.root += n_delta;
    out.clusters.push_back(cl);
  }
  const int c0 = static_cast<int>(out.clusters.size()) - (pe.cluster_end - pe.cluster_begin);
  pe.instance_root = -1;
  if (!insts.empty()) {
    // A bank of instances alone still has a root of its own facets' walk.
    if (pe.node_begin == pe.node_end) out.nodes.push_back(empty_node());
    pe.instance_root = static_cast<int>(out.nodes.size());
    append_nodes(out.nodes, tree.data(), tree.data() + tree.size(), pe.instance_root, 0);
    bytes += tree.size() * sizeof(BankNode);
    nodes += tree.size();
    std::vector<char> placed(models.size(), 0);
    for (int i : insts) {
      const int m = scene.instances[std::size_t(i)].prototype;
      int& root = out.copy_root[std::size_t(m)];
      if (root < 0) {
        const ModelTree& mt = models[std::size_t(m)];
        root = static_cast<int>(out.nodes.size());
        append_nodes(out.nodes, mt.nodes.data(), mt.nodes.data() + mt.nodes.size(), root,
                     static_cast<int>(out.tris.size()));
        out.tris.insert(out.tris.end(), mt.tris.begin(), mt.tris.end());
        out.attributes.insert(out.attributes.end(), mt.attributes.begin(), mt.attributes.end());
      }
      placed[std::size_t(m)] = 1;
      bs.instances[std::size_t(i)].root = root;
      out.clusters.push_back(instance_cluster(out.boxes[std::size_t(i)], i, -1, sbox));  // its PE: set by the caller
    }
    for (std::size_t m = 0; m < models.size(); ++m)
      if (placed[m]) bytes += model_bytes(models[m]), nodes += models[m].nodes.size();
  }
  pe.cluster_begin = c0;
  pe.cluster_end = static_cast<int>(out.clusters.size());
  pe.tri_begin = tri0;
  pe.tri_end = static_cast<int>(out.tris.size());
  pe.node_begin = node0;
  pe.node_end = static_cast<int>(out.nodes.size());
  return bytes;
}

}  // namespace

InstanceShares instance_shares(const Scene& scene, const std::vector<int>& pe_of, int num_pes, int ranks) {
  InstanceShares s;
  s.clusters.assign(std::size_t(num_pes), 0);
  s.facets.assign(std::size_t(num_pes), 0);
  std::vector<std::vector<char>> places(std::size_t(num_pes), std::vector<char>(scene.prototypes.size(), 0));
  for (std::size_t i = 0; i < scene.instances.size(); ++i) {
    ++s.clusters[std::size_t(pe_of[i])];
    places[std::size_t(pe_of[i])][std::size_t(scene.instances[i].prototype)] = 1;
  }
  // A model's copy lies in the first bank of its device that places it.
  for (int r = 0; r < ranks; ++r) {
    const PeGroup g = pe_group(num_pes, ranks, r);
    std::vector<char> held(scene.prototypes.size(), 0);
    for (int p = g.begin; p < g.end; ++p)
      for (std::size_t m = 0; m < held.size(); ++m)
        if (places[std::size_t(p)][m] && !held[m]) {
          held[m] = 1;
          s.facets[std::size_t(p)] += static_cast<int>(scene.prototypes[m].triangles.size());
        }
  }
  return s;
}

void copy_instances(const Scene& from, Scene& to) {
  to.prototypes = from.prototypes;
  to.instances = from.instances;
  to.num_objects = from.num_objects;
  for (Prototype& p : to.prototypes)
    for (Triangle& t : p.triangles) {
      if (t.attributes < 0) continue;
      to.attributes.push_back(from.attributes[std::size_t(t.attributes)]);
      t.attributes = static_cast<int>(to.attributes.size()) - 1;
    }
}

std::vector<int> deal_instances(const Scene& scene, int num_pes) {
  const std::vector<Box> boxes = instance_boxes(scene);
  std::vector<Vec3> centre(boxes.size());
  for (std::size_t i = 0; i < boxes.size(); ++i) centre[i] = boxes[i].center();
  std::vector<int> idx(centre.size()), pe_of(centre.size(), 0);
  std::iota(idx.begin(), idx.end(), 0);
  bisect(centre, std::move(idx), 0, num_pes, pe_of);
  return pe_of;
}

void add_instance_banks(const Scene& scene, const std::vector<int>& pe_of, int pe_begin, int pe_end,
                        const Box& sbox, BankedScene& bs, std::vector<int>& attributes,
                        const std::vector<int>& device_of) {
  if (!bs.tri_cluster.empty() || !bs.node_cluster.empty())
    throw std::logic_error("add_instance_banks: the pilots' maps do not follow instances");
  const std::size_t G = std::size_t(pe_end - pe_begin);
  std::vector<std::vector<int>> by_pe(G);
  std::vector<char> used(scene.prototypes.size(), 0);
  bs.instances.assign(scene.instances.size(), Instance{});
  for (std::size_t i = 0; i < scene.instances.size(); ++i) {
    Instance& in = bs.instances[i];
    std::copy(scene.instances[i].to_object.begin(), scene.instances[i].to_object.end(), in.to_object);
    in.root = -1;
    in.pe = pe_of[i];
    in.object_id = scene.num_objects + static_cast<int>(i);
    if (pe_of[i] < pe_begin || pe_of[i] >= pe_end) continue;
    by_pe[std::size_t(pe_of[i] - pe_begin)].push_back(static_cast<int>(i));
    used[std::size_t(scene.instances[i].prototype)] = 1;
  }
  std::vector<ModelTree> models(scene.prototypes.size());
  parallel_for(models.size(), [&](std::size_t m) {
    if (used[m]) models[m] = build_model(scene, scene.prototypes[m]);
  });
  Layout out;
  out.boxes = instance_boxes(scene);
  // Reserved: growing by doubling would copy (and fault in) the banks again.
  const std::size_t devices = device_of.empty() ? 1 : std::size_t(device_of.back() - device_of.front() + 1);
  std::size_t tris = bs.triangles.size(), nodes = bs.nodes.size() + 2 * G;
  for (std::size_t m = 0; m < models.size(); ++m)
    tris += devices * models[m].tris.size(), nodes += devices * models[m].nodes.size();
  out.tris.reserve(tris);
  out.nodes.reserve(nodes + scene.instances.size() / 2);
  out.clusters.reserve(bs.clusters.size() + scene.instances.size());
  if (!scene.attributes.empty()) out.attributes.reserve(tris);
  std::vector<BankArray<BankNode>> trees(G);  // side by side: each bank's alone
  parallel_for(G, [&](std::size_t p) {
    if (!by_pe[p].empty()) trees[p] = instance_tree(out.boxes, by_pe[p]);
  });
  for (std::size_t p = 0; p < G; ++p) {
    const int device = device_of.empty() ? 0 : device_of[p];
    if (device != out.device) out.device = device, out.copy_root.assign(models.size(), -1);
    std::uint64_t nodes = 0;
    const std::uint64_t bytes = lay_out_bank(scene, models, by_pe[p], trees[p], sbox, bs, p, attributes, out, nodes);
    BankArray<BankNode>().swap(trees[p]);
    if (p < bs.bank_bytes.size()) bs.bank_bytes[p] = bytes, bs.bank_nodes[p] = nodes;
  }
  for (std::size_t p = 0; p < G; ++p)
    for (int c = bs.pes[p].cluster_begin; c < bs.pes[p].cluster_end; ++c)
      out.clusters[std::size_t(c)].pe = static_cast<int>(p) + pe_begin;
  bs.triangles = std::move(out.tris);
  bs.nodes = std::move(out.nodes);
  bs.clusters = std::move(out.clusters);
  if (!scene.attributes.empty()) attributes = std::move(out.attributes);
  for (PeInfo& pe : bs.pes) partition_steps::pe_bounds(bs.clusters, pe);
}

}  // namespace opsila
