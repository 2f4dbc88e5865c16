#include "dist/collective_partition.h"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <type_traits>
#include <utility>

#include "core/page_ledger.h"
#include "core/stage_clock.h"
#include "dist/collective_balance.h"
#include "partition/instance_banks.h"
#include "partition/partition_steps.h"

namespace opsila {
namespace {

using namespace partition_steps;

// One facet on its way to the rank of its PE (Triangle::attributes: -1, or
// 0 when its vertex attributes follow in the attribute stream).
struct Shipped {
  Triangle t;
  std::int32_t cluster = 0;  // global cluster index
};

static_assert(std::is_trivially_copyable<Shipped>::value &&
                  std::is_trivially_copyable<VertexAttributes>::value && std::is_trivially_copyable<Cluster>::value,
              "sent as bytes");

// Facets in flight per rank and round: the exchange's buffer stays bounded
// (2^16 records of 56 bytes, one more per rank at most, and 64 bytes more
// for a facet with attributes: about 8 MB to send, at most R times that to
// receive) whatever the scene's size.
constexpr std::size_t kChunk = std::size_t(1) << 16;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Where every cluster goes: the whole scene's clusters in partition_scene's
// order (object, then the order the cuts made them), placed by the same
// bisection, then sorted by PE (stably) as partition_scene sorts them.
struct Placement {
  std::vector<ClusterSummary> clusters;  // global order (sorted by PE)
  std::vector<int> pe;                   // of each
  std::vector<int> global_of_local;      // this rank's clusters -> global index
};

// The table bisected as partition_scene bisects its clusters: by facets,
// by the sampled rays crossing them and a tenth on the facets (--balance
// work), or by each level's measured work and a tenth on the facets.
Placement place_clusters(const ClusterTable& t, const ShareClusters& split, int num_pes, Ranks& ranks) {
  const std::vector<ClusterSummary>& all = t.clusters;
  const std::size_t L = std::size_t(t.levels);
  std::int64_t heat = 0;
  std::size_t facets = 0;
  for (std::size_t k = 0; k < all.size(); ++k) {
    heat += heat_of(t.work.data() + k * L, t.levels);
    facets += all[k].facets;
  }
  std::vector<ClusterBuild> table(all.size());
  for (std::size_t k = 0; k < all.size(); ++k) {
    for (int a = 0; a < 3; ++a) table[k].c[a] = all[k].c[a];
    table[k].weight = double(all[k].facets);
    if (heat > 0 && t.sampled)
      table[k].weight = sampled_weight(all[k].facets, facets, heat_of(t.work.data() + k * L, t.levels), heat);
    else if (heat > 0)
      table[k].work = measured_weights(t.work.data() + k * L, t.levels, heat, all[k].facets, facets);
  }
  std::vector<int> idx(all.size());
  std::iota(idx.begin(), idx.end(), 0);
  if (heat > 0 && !t.sampled)
    assign_regions_measured(table, idx, 0, num_pes);
  else
    assign_regions(table, idx, 0, num_pes);
  std::stable_sort(idx.begin(), idx.end(), [&](int a, int b) { return table[a].pe < table[b].pe; });
  Placement out;
  out.global_of_local.assign(split.clusters.size(), -1);
  for (std::size_t g = 0; g < idx.size(); ++g) {
    const ClusterSummary& s = all[std::size_t(idx[g])];
    out.clusters.push_back(s);
    out.pe.push_back(table[std::size_t(idx[g])].pe);
    if (s.spread)
      out.global_of_local[std::size_t(split.spread[std::size_t(s.local)].local)] = static_cast<int>(g);
    else if (s.rank == ranks.rank())
      out.global_of_local[std::size_t(s.local)] = static_cast<int>(g);
  }
  return out;
}

// Records for each rank, laid out in rank order, and their counts.
template <typename T>
std::vector<std::uint64_t> lay_out(const std::vector<std::vector<T>>& to, std::vector<unsigned char>& send) {
  std::vector<std::uint64_t> counts;
  for (const std::vector<T>& records : to) {
    counts.push_back(records.size());
    const std::vector<unsigned char> b = bytes_of(records);
    send.insert(send.end(), b.begin(), b.end());
  }
  return counts;
}

template <typename T>
std::vector<T> exchange_records(Ranks& ranks, const std::vector<std::vector<T>>& to) {
  std::vector<unsigned char> send, recv;
  const std::vector<std::uint64_t> counts = lay_out(to, send);
  ranks.all_to_all(send, counts, sizeof(T), recv);
  return records_of<T>(recv);
}

// The rank's own part of the scene: its clusters' facets (and their
// attributes) with the scene's materials and textures, and the clusters as
// the bank build wants them (PEs numbered in the group). Filled round by
// round as the facets arrive, so the records are never held all at once.
struct OwnPart {
  Scene scene;
  std::vector<ClusterBuild> clusters;
  int first_cluster = 0;  // global index of the first
  void add(const std::vector<Shipped>& facets, const std::vector<VertexAttributes>& attributes) {
    std::size_t next = 0;
    for (const Shipped& s : facets) {
      Triangle t = s.t;
      if (t.attributes >= 0) {
        t.attributes = static_cast<int>(scene.attributes.size());
        scene.attributes.push_back(attributes[next++]);
      }
      clusters[std::size_t(s.cluster - first_cluster)].tris.push_back(static_cast<int>(scene.triangles.size()));
      scene.triangles.push_back(t);
    }
  }
};

// One destination's facets, its clusters in local order, sent `quota` a
// round (the last round may send fewer).
struct Stream {
  std::vector<std::size_t> clusters;  // local cluster indices
  std::size_t next = 0, facet = 0;    // the next facet to send: clusters[next], its facet-th
  std::uint64_t facets = 0, quota = 0;
};

// Each destination's facets spread evenly over the rounds, which every rank
// runs alike (enough for the rank with the most facets, kChunk a round).
// Sent cluster after cluster instead, every rank sends to the same rank at
// once (the ranks' clusters lie in much the same order), which receives up
// to R times what it sends and so holds most of its share and of what it
// receives at once: the peak of the rank served first (docs/BENCHMARKS.md
// "Capacity"). Evenly, each rank receives about what it sends each round.
// A round sends at most kChunk + R facets. Returns the rounds; `attributes`
// (whether this rank's share has vertex attributes) becomes whether any
// rank's has (one collective for both).
std::uint64_t plan_streams(const std::vector<ClusterBuild>& local, const Placement& pl, int num_pes, Ranks& ranks,
                           std::vector<Stream>& streams, bool& attributes) {
  const int R = ranks.size();
  streams.assign(std::size_t(R), Stream());
  std::uint64_t facets = 0;
  for (std::size_t c = 0; c < local.size(); ++c) {
    if (local[c].tris.empty()) continue;  // a spread cluster's part on other ranks only
    const int pe = pl.pe[std::size_t(pl.global_of_local[c])];
    Stream& s = streams[std::size_t(rank_of_pe(num_pes, R, pe))];
    s.clusters.push_back(c);
    s.facets += local[c].tris.size();
    facets += local[c].tris.size();
  }
  std::vector<std::uint64_t> most{attributes ? 1u : 0u, facets};
  ranks.max(most);
  attributes = most[0] != 0;
  const std::uint64_t rounds = (most[1] + kChunk - 1) / kChunk;
  for (Stream& s : streams) s.quota = rounds ? (s.facets + rounds - 1) / rounds : 0;
  return rounds;
}

// Each local cluster's facets to the rank of its PE, round by round
// (plan_streams), into `own` as they come: each cluster's from one rank in
// the order that rank held them (a spread cluster's from several: see
// order_spread).
void exchange_facets(const Scene& scene, const std::vector<ClusterBuild>& local, const Placement& pl,
                     int num_pes, Ranks& ranks, OwnPart& own, PageLedger* sent) {
  const std::size_t R = std::size_t(ranks.size());
  bool attributes = !scene.attributes.empty();  // a second stream only when needed
  std::vector<Stream> streams;
  const std::uint64_t rounds = plan_streams(local, pl, num_pes, ranks, streams, attributes);
  for (std::uint64_t round = 0; round < rounds; ++round) {
    std::vector<std::vector<Shipped>> to(R);
    std::vector<std::vector<VertexAttributes>> to_attributes(R);
    for (std::size_t dest = 0; dest < R; ++dest) {
      Stream& st = streams[dest];
      for (std::uint64_t n = 0; n < st.quota && st.next < st.clusters.size(); ++n) {
        const std::size_t cluster = st.clusters[st.next];
        const int tri = local[cluster].tris[st.facet];
        if (++st.facet == local[cluster].tris.size()) ++st.next, st.facet = 0;
        Shipped s;
        s.t = scene.triangles[std::size_t(tri)];
        if (sent) sent->done(std::size_t(tri));
        s.cluster = pl.global_of_local[cluster];
        if (s.t.attributes >= 0) to_attributes[dest].push_back(scene.attributes[std::size_t(s.t.attributes)]);
        s.t.attributes = s.t.attributes >= 0 ? 0 : -1;
        to[dest].push_back(s);
      }
    }
    if (sent) sent->release();  // packed: the share's pages sent whole go
    const std::vector<Shipped> got = exchange_records(ranks, to);
    own.add(got, attributes ? exchange_records(ranks, to_attributes) : std::vector<VertexAttributes>());
  }
}

}  // namespace

namespace {

// The group's clusters, empty, ready for their facets.
OwnPart own_part(const Scene& share, const Placement& pl, const PeGroup& group) {
  OwnPart own;
  own.scene.materials = share.materials;
  own.scene.textures = share.textures;
  own.scene.smooth = share.smooth;
  std::uint64_t facets = 0;
  int g0 = 0;
  while (g0 < int(pl.pe.size()) && pl.pe[std::size_t(g0)] < group.begin) ++g0;
  own.first_cluster = g0;
  for (int g = g0; g < int(pl.pe.size()) && pl.pe[std::size_t(g)] < group.end; ++g) {
    ClusterBuild cb;
    const ClusterSummary& s = pl.clusters[std::size_t(g)];
    for (int a = 0; a < 3; ++a) cb.c[a] = s.c[a], cb.box.lo[a] = s.lo[a], cb.box.hi[a] = s.hi[a];
    cb.pe = pl.pe[std::size_t(g)] - group.begin;
    cb.weight = double(s.facets);
    cb.tris.reserve(s.facets);
    facets += s.facets;
    own.clusters.push_back(std::move(cb));
  }
  own.scene.triangles.reserve(facets);
  return own;
}

// A spread cluster's facets came from several ranks, round by round: put in
// one process's order (make_cluster's), which is the facet ids' order, a
// facet's fan in fan order (a total order: the result does not depend on
// the order they came in).
void order_spread(OwnPart& own, const Placement& pl) {
  const auto& tris = own.scene.triangles;
  for (std::size_t c = 0; c < own.clusters.size(); ++c)
    if (pl.clusters[std::size_t(own.first_cluster) + c].spread)
      std::sort(own.clusters[c].tris.begin(), own.clusters[c].tris.end(),
                [&](int a, int b) {
                  const Triangle &x = tris[std::size_t(a)], &y = tris[std::size_t(b)];
                  return x.facet_id != y.facet_id ? x.facet_id < y.facet_id : x.fan < y.fan;
                });
}

// The texels of the maps the group's facets use, decoded now if the share
// was read without them; the bytes of texels held.
std::uint64_t decode_maps(const SceneShare& share, Scene& own) {
  if (share.decode_maps) return share.decode_maps(own);
  std::uint64_t bytes = 0;
  for (const Texture& t : own.textures) {
    if (t.pixels_later) throw std::logic_error("bank_share: texture maps read for later without a decoder");
    bytes += t.texels.size() * sizeof(std::uint32_t);
  }
  return bytes;
}

// The group's banks from its own part: partition_scene's steps 3-4 on the
// group's PEs only (numbered from 0, as keep_group_banks leaves them).
BankedScene group_banks(OwnPart& own, const Box& sbox, const PeGroup& group, const std::vector<int>& inst_pe,
                        bool pilot, std::vector<char>& used) {
  BankedScene loc;
  loc.num_pes = group.size();
  FacetMaps maps;
  maps.pilot = pilot;
  std::vector<std::pair<int, int>> ranges;
  fill_banks(own.scene, sbox, own.clusters, loc, maps, ranges, &own.scene.triangles);
  const std::size_t facets = own.scene.triangles.size();
  // The bank facets are copies (their attributes' indices in `maps`): the
  // received ones go before the BVHs are built.
  own.scene.triangles = std::vector<Triangle>();
  describe_pes(own.clusters, ranges, maps, facets, loc);
  if (!inst_pe.empty()) {  // the group's PEs numbered from 0 here, the table's PEs global
    std::vector<int> local(inst_pe.size());
    for (std::size_t i = 0; i < local.size(); ++i) local[i] = inst_pe[i] - group.begin;
    add_instance_banks(own.scene, local, 0, group.size(), sbox, loc, maps.attributes);
    for (std::size_t i = 0; i < local.size(); ++i) loc.instances[i].pe = inst_pe[i];
  }
  if (pilot) node_clusters(loc);
  bank_attributes(own.scene, maps.attributes, loc, &used);
  loc.source = std::move(maps.source);
  return loc;
}

// Everything the other ranks built that every PE must know: cluster
// spheres and boxes, the PE table, bank sizes, routing. `loc` (the group's
// banks) becomes what keep_group_banks leaves of the whole scene's banks.
BankedScene share_tables(const Scene& share, const Box& sbox, const Placement& pl, const PeGroup& group,
                         int num_pes, int first_cluster, const std::vector<char>& used, Ranks& ranks,
                         BankedScene& loc, const InstanceShares& inst) {
  const std::size_t P = std::size_t(num_pes), T = share.textures.size();
  // Vertex attributes are one flag for the whole scene (FrameParams): a
  // rank whose facets have none still gives each of them an empty record.
  std::vector<std::uint64_t> any{loc.attributes.empty() ? 0u : 1u};
  ranks.max(any);
  if (any[0] && loc.attributes.empty()) {
    BankAttributes none{};
    none.flags = 0;
    none.map_kd = none.map_ka = -1;
    loc.attributes.assign(loc.triangles.size(), none);
    for (std::size_t p = 0; p < loc.pes.size(); ++p)
      loc.bank_bytes[p] += std::uint64_t(loc.pes[p].tri_end - loc.pes[p].tri_begin) * sizeof(BankAttributes);
  }
  std::vector<std::uint64_t> v(3 * P + T, 0);  // bank bytes, texture bytes, bank nodes, textures used
  for (int p = group.begin; p < group.end; ++p) {
    v[std::size_t(p)] = loc.bank_bytes[std::size_t(p - group.begin)];
    v[P + std::size_t(p)] = loc.texture_bytes[std::size_t(p - group.begin)];
    v[2 * P + std::size_t(p)] = loc.bank_nodes[std::size_t(p - group.begin)];
  }
  for (std::size_t t = 0; t < T && t < used.size(); ++t) v[3 * P + t] = used[t];
  ranks.max(v);
  BankedScene bs;
  bs.num_pes = num_pes;
  bs.bank_bytes.assign(v.begin(), v.begin() + std::ptrdiff_t(P));
  bs.texture_bytes.assign(v.begin() + std::ptrdiff_t(P), v.begin() + std::ptrdiff_t(2 * P));
  bs.bank_nodes.assign(v.begin() + std::ptrdiff_t(2 * P), v.begin() + std::ptrdiff_t(3 * P));
  const std::vector<char> used_anywhere(v.begin() + std::ptrdiff_t(3 * P), v.end());
  bs.triangles = std::move(loc.triangles);
  bs.nodes = std::move(loc.nodes);
  bs.attributes = std::move(loc.attributes);
  bs.textures = std::move(loc.textures);
  for (BankTexture& t : bs.textures) t.pe += group.begin;
  bs.texels = std::move(loc.texels);
  bs.source = std::move(loc.source);
  bs.tri_cluster = std::move(loc.tri_cluster);
  for (int& c : bs.tri_cluster) c += first_cluster;
  bs.node_cluster = std::move(loc.node_cluster);
  for (int& c : bs.node_cluster)
    if (c >= 0) c += first_cluster;

  for (Cluster& c : loc.clusters) c.pe += group.begin;
  bs.clusters = records_of<Cluster>(ranks.all_gather(bytes_of(loc.clusters)));
  bs.instances = std::move(loc.instances);
  // Each PE's instance clusters follow its own (partition/instance_banks.h).
  std::size_t instance_clusters = 0;
  for (int p = 0; p < num_pes && !inst.clusters.empty(); ++p) {
    if (p < group.begin) first_cluster += inst.clusters[std::size_t(p)];
    instance_clusters += std::size_t(inst.clusters[std::size_t(p)]);
  }
  if (bs.clusters.size() != pl.pe.size() + instance_clusters)
    throw std::logic_error("partition_share: the ranks' clusters disagree");
  const int own_end = first_cluster + static_cast<int>(loc.clusters.size());
  for (int c = 0; c < int(bs.clusters.size()); ++c)
    if (c < first_cluster || c >= own_end) bs.clusters[std::size_t(c)].root = -1;

  bs.pes.resize(P);
  std::size_t c = 0, placed = 0;  // the global table's clusters, the plan's
  std::uint64_t tri = 0;
  for (int p = 0; p < num_pes; ++p) {
    PeInfo& pe = bs.pes[std::size_t(p)];
    pe.cluster_begin = static_cast<int>(c);
    pe.tri_begin = static_cast<int>(tri);
    for (; placed < pl.pe.size() && pl.pe[placed] == p; ++placed, ++c) tri += pl.clusters[placed].facets;
    if (!inst.clusters.empty()) c += std::size_t(inst.clusters[std::size_t(p)]), tri += inst.facets[std::size_t(p)];
    pe.cluster_end = static_cast<int>(c);
    pe.tri_end = static_cast<int>(tri);
    const bool mine = p >= group.begin && p < group.end;
    pe.node_begin = mine ? loc.pes[std::size_t(p - group.begin)].node_begin : 0;
    pe.node_end = mine ? loc.pes[std::size_t(p - group.begin)].node_end : 0;
    pe.instance_root = mine ? loc.pes[std::size_t(p - group.begin)].instance_root : -1;
    pe_bounds(bs.clusters, pe);
  }
  build_routing(bs, sbox);
  global_tables(share, bs);
  scene_bytes(bs, texture_once(share, used_anywhere));
  return bs;
}

// For the pilots (dist/pilot.h): the cluster of each facet of the share
// and the facets of every cluster.
void note_clusters(const ShareClusters& split, const Placement& pl, std::size_t facets, PreparedBanks& out) {
  out.facet_cluster.assign(facets, -1);
  for (std::size_t i = 0; i < split.clusters.size(); ++i)
    for (int t : split.clusters[i].tris) out.facet_cluster[std::size_t(t)] = pl.global_of_local[i];
  for (const ClusterSummary& s : pl.clusters) out.cluster_facets.push_back(s.facets);
}

}  // namespace

PreparedBanks bank_share(Scene& share, int num_pes, int routing, const PeGroup& group, Ranks& ranks,
                         const ShareBalance& how) {
  if (share.share.ranks != ranks.size() || share.share.rank != ranks.rank() || group.rank != ranks.rank())
    throw std::invalid_argument("bank_share: one share per rank, read for this rank");
  ranks.begin_collective();  // from here a failure on one rank ends them all
  StageClock clock(PrepareStage::partition);  // the exchange and the tables too; the bank BVHs are their own stage
  const bool split_flat = routing == OPSILA_ROUTING_SPHERES;
  PreparedBanks out;
  out.group = group;
  out.balance = how.measured ? Balance::measured : how.sample ? Balance::work : Balance::facets;
  const ShareHeat heat{how.measured, how.sample};
  ShareFigures& figures = out.share;
  auto t0 = std::chrono::steady_clock::now();
  figures.active = true;
  figures.facets_read = share.triangles.size();
  figures.read_seconds = share.share.read_seconds;
  Vec3 slo, shi;
  share.bounds(slo, shi);
  Box sbox;
  sbox.grow(slo.data());
  sbox.grow(shi.data());
  // Progress: the cuts are about half of the stage, the exchange the rest.
  ShareClusters split;
  if (how.clusters && how.reuse) {
    if (how.keep_share)
      split = *how.clusters;
    else
      split = std::move(*how.clusters);  // the last partition
  } else {
    split = split_share(share, sbox, num_pes, split_flat, ranks, [&clock](double f) { clock.progress(0.5 * f); });
    if (how.clusters) *how.clusters = split;
  }
  ClusterTable table = gather_clusters(share, split, heat, ranks);
  if (heat.levels() > 0) cut_hot_clusters(share, heat, num_pes, split, table, ranks);
  const Placement pl = place_clusters(table, split, num_pes, ranks);
  table = ClusterTable();
  if (how.keep_share) note_clusters(split, pl, share.triangles.size(), out);
  figures.partition_seconds = seconds_since(t0);
  clock.progress(0.5);

  t0 = std::chrono::steady_clock::now();
  OwnPart own = own_part(share, pl, group);
  // A share that is not kept gives its pages back as they are sent
  // (core/page_ledger.h): it and the facets received are never both whole.
  std::optional<PageLedger> sent;
  if (!how.keep_share) sent.emplace(share.triangles.data(), share.triangles.size(), sizeof(Triangle));
  exchange_facets(share, split.clusters, pl, num_pes, ranks, own, sent ? &*sent : nullptr);
  // Instances are not dealt: every rank holds them all and banks its PEs'.
  const std::vector<int> inst_pe = share.instances.empty() ? std::vector<int>() : deal_instances(share, num_pes);
  if (!inst_pe.empty()) copy_instances(share, own.scene);
  // Sent: the share as read is no longer needed (its materials, textures
  // and figures stay).
  split = ShareClusters();
  if (!how.keep_share) {
    share.triangles = std::vector<Triangle>();
    share.attributes = std::vector<VertexAttributes>();
  }
  order_spread(own, pl);
  figures.exchange_seconds = seconds_since(t0);
  clock.progress(0.9);
  figures.facets_held = own.scene.triangles.size();

  t0 = std::chrono::steady_clock::now();
  figures.texture_bytes = decode_maps(share.share, own.scene);  // the maps its facets use, no others
  std::vector<char> used;
  BankedScene loc = group_banks(own, sbox, group, inst_pe, how.pilot, used);
  own.scene = Scene();
  out.scene = share_tables(share, sbox, pl, group, num_pes, own.first_cluster, used, ranks, loc,
                           inst_pe.empty() ? InstanceShares() : instance_shares(share, inst_pe, num_pes, ranks.size()));
  figures.bank_seconds = seconds_since(t0);
  out.tri_base = out.scene.pes[std::size_t(group.begin)].tri_begin;
  ranks.end_collective();
  return out;
}

}  // namespace opsila
