#include "partition/pe_group.h"

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "scene/scene.h"

namespace opsila {

PeGroup pe_group(int num_pes, int ranks, int rank) {
  if (ranks > num_pes)
    throw InputError(std::to_string(ranks) + " MPI ranks for " + std::to_string(num_pes) +
                     " PEs: every rank needs at least one PE (use --pes " + std::to_string(ranks) +
                     " or more, or fewer ranks)");
  PeGroup g;
  g.rank = rank;
  g.ranks = ranks;
  g.begin = static_cast<int>(std::int64_t(rank) * num_pes / ranks);
  g.end = static_cast<int>(std::int64_t(rank + 1) * num_pes / ranks);
  return g;
}

int rank_of_pe(int num_pes, int ranks, int pe) {
  // Largest r with r*P/R <= pe.
  int r = static_cast<int>((std::int64_t(pe) * ranks + ranks - 1) / num_pes);
  while (r > 0 && std::int64_t(r) * num_pes / ranks > pe) --r;
  while (r + 1 < ranks && std::int64_t(r + 1) * num_pes / ranks <= pe) ++r;
  return r;
}

std::vector<int> devices_of_pes(int num_pes, int ranks) {
  std::vector<int> r(static_cast<std::size_t>(num_pes));
  for (int p = 0; p < num_pes; ++p) r[std::size_t(p)] = rank_of_pe(num_pes, ranks, p);
  return r;
}

int keep_group_banks(BankedScene& bs, const PeGroup& group) {
  if (group.all()) return 0;
  const PeInfo& first = bs.pes[group.begin];
  const PeInfo& last = bs.pes[group.end - 1];
  const int t0 = first.tri_begin, t1 = last.tri_end;
  const int n0 = first.node_begin, n1 = last.node_end;
  if (t0 > t1 || n0 > n1) throw std::logic_error("keep_group_banks: banks are not contiguous in PE order");
  bs.triangles = BankArray<BankTriangle>(bs.triangles.begin() + t0, bs.triangles.begin() + t1);
  bs.nodes = BankArray<BankNode>(bs.nodes.begin() + n0, bs.nodes.begin() + n1);
  // The pilots' maps, when kept (PartitionUse::pilot_maps).
  const auto slice = [](std::vector<int>& v, int b, int e) {
    if (!v.empty()) v = std::vector<int>(v.begin() + b, v.begin() + e);
  };
  slice(bs.tri_cluster, t0, t1);
  slice(bs.source, t0, t1);
  slice(bs.node_cluster, n0, n1);
  // Per-facet attributes follow the facets; the texture copies (grouped by
  // bank, in PE order) and their texels keep only this group's.
  if (!bs.attributes.empty())
    bs.attributes = BankArray<BankAttributes>(bs.attributes.begin() + t0, bs.attributes.begin() + t1);
  std::size_t k0 = bs.textures.size(), k1 = 0;
  for (std::size_t k = 0; k < bs.textures.size(); ++k)
    if (bs.textures[k].pe >= group.begin && bs.textures[k].pe < group.end) k0 = std::min(k0, k), k1 = k + 1;
  if (k0 >= k1) k0 = k1 = 0;
  // Banks share the texels of a map (bank_attributes): keep the span of them.
  int x0 = k0 < k1 ? INT32_MAX : 0, x1 = 0;
  for (std::size_t k = k0; k < k1; ++k)
    x0 = std::min(x0, bs.textures[k].texel_begin),
    x1 = std::max(x1, bs.textures[k].texel_begin + bs.textures[k].width * bs.textures[k].height);
  bs.textures = std::vector<BankTexture>(bs.textures.begin() + k0, bs.textures.begin() + k1);
  for (BankTexture& t : bs.textures) t.texel_begin -= x0;
  bs.texels = BankArray<std::uint32_t>(bs.texels.begin() + x0, bs.texels.begin() + x1);
  for (BankAttributes& a : bs.attributes) {
    if (a.map_kd >= 0) a.map_kd -= static_cast<int>(k0);
    if (a.map_ka >= 0) a.map_ka -= static_cast<int>(k0);
  }
  for (BankNode& node : bs.nodes)
    for (int k = 0; k < OPSILA_BVH_WIDTH; ++k) {
      if (node.count[k] == 0) node.child[k] -= n0;      // inner: a node
      else if (node.count[k] == OPSILA_INSTANCE_LEAF) continue;  // an instance: its index
      else if (node.count[k] > 0) node.child[k] -= t0;  // leaf: its first facet
    }
  for (int p = 0; p < bs.num_pes; ++p) {
    PeInfo& pe = bs.pes[p];
    const bool mine = p >= group.begin && p < group.end;
    pe.node_begin = mine ? pe.node_begin - n0 : 0;  // other banks are not on this device
    pe.node_end = mine ? pe.node_end - n0 : 0;
    pe.instance_root = mine && pe.instance_root >= 0 ? pe.instance_root - n0 : -1;
  }
  for (Instance& in : bs.instances) in.root = in.pe >= group.begin && in.pe < group.end ? in.root - n0 : -1;
  for (Cluster& c : bs.clusters) {
    const bool mine = c.pe >= group.begin && c.pe < group.end;
    c.root = !mine ? -1 : c.root >= 0 ? c.root - n0 : c.root;  // an instance's: -2 - the instance
  }
  return t0;
}

}  // namespace opsila
