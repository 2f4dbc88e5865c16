#include "frame/stats.h"

#include <algorithm>
#include <cstdint>
#include <map>

#include "scene/instances.h"
#include "device/counters.h"
#include "device/descriptors.h"
#include "opsila_shared.h"

namespace opsila {

double test_occupancy(const RenderStats& st) {
  double done = 0, allowed = 0;
  for (const auto& level : st.counters) {
    std::uint64_t most = 0;
    for (const auto& pe : level) {
      const std::uint64_t tests = pe[OPSILA_STAT_TRI_TESTS] + pe[OPSILA_STAT_BOX_TESTS];
      done += double(tests);
      most = std::max(most, tests);
    }
    allowed += double(most) * double(level.size());
  }
  return allowed > 0 ? done / allowed : 0.0;
}

namespace {

nlohmann::json counters_object(const std::vector<std::uint64_t>& values) {
  std::vector<std::uint64_t> all(OPSILA_STAT_COUNT, 0);
  std::copy_n(values.begin(), std::min<std::size_t>(values.size(), OPSILA_STAT_COUNT), all.begin());
  nlohmann::json out = nlohmann::json::object();
  for (int i = 0; i < OPSILA_STAT_COUNT; ++i) out[stat_name(i)] = all[std::size_t(i)];
  const CounterSums sums = counter_sums(all.data());
  out["finished"] = sums.finished;  // every ray that finishes at this level
  out["spawned"] = sums.spawned;
  return out;
}

// Per level: totals over the PEs and each PE's counters.
nlohmann::json levels_json(const RenderStats& s) {
  nlohmann::json levels = nlohmann::json::array();
  for (std::size_t level = 0; level < s.counters.size(); ++level) {
    std::vector<std::uint64_t> totals(OPSILA_STAT_COUNT, 0);
    nlohmann::json pes = nlohmann::json::array();
    for (std::size_t pe = 0; pe < s.counters[level].size(); ++pe) {
      const std::vector<std::uint64_t>& values = s.counters[level][pe];
      for (int i = 0; i < OPSILA_STAT_COUNT && i < static_cast<int>(values.size()); ++i)
        totals[i] += values[i];
      nlohmann::json entry = counters_object(values);
      entry["pe"] = pe;
      pes.push_back(std::move(entry));
    }
    levels.push_back({{"level", level}, {"totals", counters_object(totals)}, {"pes", std::move(pes)}});
  }
  return levels;
}

// Every launch, and per kernel name the launches and their total time.
void add_launches(nlohmann::json& j, const RenderStats& s) {
  nlohmann::json launches = nlohmann::json::array();
  std::map<std::string, std::pair<std::uint64_t, double>> by_name;
  for (const LaunchRecord& launch : s.launches) {
    nlohmann::json entry = {{"name", launch.name}, {"round", launch.round}, {"seconds", launch.seconds}};
    if (launch.queued >= 0) entry["queued"] = launch.queued, entry["started"] = launch.started;
    if (launch.round == LaunchRecord::kFoldedRound) entry["launches"] = launch.launches;
    launches.push_back(std::move(entry));
    auto& summary = by_name[launch.name];
    summary.first += launch.launches;
    summary.second += launch.seconds;
  }
  j["launches"] = std::move(launches);
  nlohmann::json summary = nlohmann::json::object();
  for (const auto& [name, entry] : by_name)
    summary[name] = {{"count", entry.first}, {"total_seconds", entry.second}};
  j["launch_summary"] = std::move(summary);
}

nlohmann::json memory_json(const RenderStats& s) {
  std::uint64_t bank_max = 0, bank_sum = 0;
  for (std::uint64_t bytes : s.bank_bytes) {
    bank_max = std::max(bank_max, bytes);
    bank_sum += bytes;
  }
  nlohmann::json m = {{"bank_bytes", s.bank_bytes},
                 {"bank_bytes_max", bank_max},
                 {"bank_bytes_mean", s.bank_bytes.empty() ? 0.0
                                                          : static_cast<double>(bank_sum) /
                                                                static_cast<double>(s.bank_bytes.size())},
                 {"global_bytes", s.global_bytes},
                 {"replicated_bytes", s.replicated_bytes}};
  // Texture maps live in the banks whose facets use them (a shared one in
  // each such bank): what each bank holds against one full copy.
  std::uint64_t texture_max = 0;
  for (std::uint64_t bytes : s.texture_bytes) texture_max = std::max(texture_max, bytes);
  m["texture_bytes"] = s.texture_bytes;
  m["texture_bytes_max"] = texture_max;
  m["texture_replicated_bytes"] = s.texture_replicated_bytes;
  return m;
}


nlohmann::json traffic_json(const RenderStats& s) {
  // traffic[level] is a flat P x P array (src * P + dst): emit it as rows.
  nlohmann::json traffic = nlohmann::json::array();
  const std::size_t p = static_cast<std::size_t>(std::max(0, s.num_pes));
  for (const std::vector<std::uint64_t>& flat : s.traffic) {
    nlohmann::json matrix = nlohmann::json::array();
    if (p > 0 && flat.size() == p * p) {
      for (std::size_t src = 0; src < p; ++src)
        matrix.push_back(std::vector<std::uint64_t>(flat.begin() + src * p, flat.begin() + (src + 1) * p));
    } else {
      matrix = flat;  // unexpected shape: keep the raw numbers rather than drop them
    }
    traffic.push_back(std::move(matrix));
  }
  return traffic;
}

}  // namespace

nlohmann::json prepare_json(const PrepareTimes& t) {
  nlohmann::json j = nlohmann::json::object();
  for (int k = 0; k < kPrepareStages; ++k)
    j[std::string(stage_key(static_cast<PrepareStage>(k))) + "_seconds"] = t.seconds[k];
  j["peak_host_bytes"] = t.peak_host_bytes;
  nlohmann::json at_end = nlohmann::json::object();
  for (int k = 0; k < kPrepareStages; ++k)
    if (t.peak_at_end[k]) at_end[stage_key(static_cast<PrepareStage>(k))] = t.peak_at_end[k];
  j["peak_host_bytes_at_end"] = at_end;
  return j;
}

// What a triangle costs: this device's planned memory and this process's
// peak resident set, over the scene's triangles (every rank's). Apart from
// "memory", which is the same for any rank count.
nlohmann::json triangle_cost_json(const RenderStats& s, std::size_t triangles) {
  const double per = triangles ? 1.0 / double(triangles) : 0.0;
  return {{"triangles", triangles},
          {"device_bytes", s.device_bytes},
          {"device_bytes_per_triangle", double(s.device_bytes) * per},
          {"host_peak_bytes", s.prepare.peak_host_bytes},
          {"host_peak_bytes_per_triangle", double(s.prepare.peak_host_bytes) * per}};
}

nlohmann::json stats_json(const RenderResult& result, const Scene& scene,
                          const RenderSettings& settings, const std::string& device_description) {
  const RenderStats& s = result.stats;
  nlohmann::json j;
  j["version"] = OPSILA_VERSION;
  j["device"] = device_description;
  j["width"] = result.width;
  j["height"] = result.height;
  j["depth"] = scene.max_depth;
  j["pes"] = s.num_pes > 0 ? s.num_pes : settings.num_pes;
  j["bank_capacity"] = s.bank_capacity > 0 ? s.bank_capacity : settings.bank_capacity;
  j["clusters"] = s.num_clusters;
  j["routing"] = s.routing == OPSILA_ROUTING_SPHERES ? "spheres" : "boxes";
  j["balance"] = balance_name(s.balance);
  if (s.balance == Balance::measured) j["pilot"] = {{"frames", s.pilot_frames}, {"seconds", s.pilot_seconds}};
  j["work_group_size"] = s.work_group_size;
  j["bvh_nodes"] = s.quantised_nodes ? "quantised" : "float";
  j["rounds"] = s.rounds;
  j["scene"] = {{"triangles", scene.total_triangles()},
                {"facets", scene.num_facets},
                {"objects", scene.num_objects},
                {"lights", scene.lights.size()}};
  // Instances: the models' triangles held once each, and those they stand for.
  if (!scene.instances.empty())
    j["scene"]["instances"] = {{"count", scene.instances.size()},
                               {"models", scene.prototypes.size()},
                               {"model_triangles", prototype_triangles(scene)},
                               {"instanced_triangles", instanced_triangles(scene)}};

  const RayCounts& rays = result.rays;
  const std::uint64_t total_rays = rays.total();
  j["rays"] = {{"primary", rays.primary},
               {"primary_hits", rays.primary_hits},
               {"secondary", rays.secondary},
               {"shadow", rays.shadow},
               {"total", total_rays}};
  j["render_seconds"] = s.render_seconds;
  j["readback_seconds"] = s.readback_seconds;
  j["kernel_compile_seconds"] = s.kernel_compile_seconds;
  j["mrays_per_s"] = s.render_seconds > 0 ? static_cast<double>(total_rays) / s.render_seconds / 1e6 : 0.0;
  j["prepare"] = prepare_json(s.prepare);

  j["levels"] = levels_json(s);

  // Every descriptor created (primary hits and spawned rays; forwards only
  // move them between PEs) must finish exactly once: shaded, missed,
  // occluded or lit.
  j["descriptors"] = {{"spawned", s.descriptors_spawned},
                      {"finished", s.descriptors_finished},
                      {"forwards", s.forwards},
                      {"overflow_deferrals", s.overflow_deferrals},
                      {"waiting_peak", s.waiting_peak},
                      {"throttled_rounds", s.throttled_rounds}};
  j["balanced"] = s.descriptors_spawned == s.descriptors_finished;
  // Destination choice over the frame: sphere tests plus PE-box and
  // routing-node tests, and the descriptors the PEs processed.
  std::uint64_t sphere = 0, route = 0, traced = 0;
  for (const auto& level : s.counters)
    for (const auto& c : level) {
      sphere += c[OPSILA_STAT_SPHERE_TESTS];
      route += c[OPSILA_STAT_ROUTE_TESTS];
      traced += c[OPSILA_STAT_TRACED];
    }
  j["routing_tests"] = {{"sphere", sphere}, {"route", route}, {"total", sphere + route}};
  j["descriptors"]["processed"] = traced;

  add_launches(j, s);

  j["memory"] = memory_json(s);
  // Per unique triangle: the scene's own and the models' (once each).
  j["triangle_cost"] = triangle_cost_json(s, scene.total_triangles() + prototype_triangles(scene));

  j["traffic"] = traffic_json(s);
  if (!s.ranks.empty()) j["mpi"] = ranks_json(s.ranks);
  return j;
}

RankTraffic rank_traffic(const std::vector<RankReport>& reports) {
  RankTraffic t;
  const std::size_t R = reports.size();
  std::size_t rounds = 0;
  for (const RankReport& r : reports) rounds = std::max(rounds, r.sent.size());
  t.rounds.assign(rounds, std::vector<std::vector<std::uint64_t>>(R, std::vector<std::uint64_t>(R, 0)));
  t.total.assign(R, std::vector<std::uint64_t>(R, 0));
  t.sent_by_rank.assign(R, 0);
  t.received_by_rank.assign(R, 0);
  // Sent by src to dst in a round must equal what dst counted from src.
  bool mirrored = true;
  for (std::size_t src = 0; src < R; ++src)
    for (std::size_t k = 0; k < reports[src].sent.size(); ++k)
      for (std::size_t dst = 0; dst < R && dst < reports[src].sent[k].size(); ++dst) {
        const std::uint64_t n = reports[src].sent[k][dst];
        t.rounds[k][src][dst] = n;
        t.total[src][dst] += n;
        if (dst != src) t.sent += n, t.sent_by_rank[src] += n;
        const auto& back = reports[dst].received;
        if (k >= back.size() || src >= back[k].size() || back[k][src] != n) mirrored = false;
      }
  for (std::size_t d = 0; d < R; ++d)
    for (const auto& row : reports[d].received)
      for (std::size_t src = 0; src < row.size(); ++src)
        if (src != d) t.received += row[src], t.received_by_rank[d] += row[src];
  t.balanced = mirrored && t.sent == t.received;
  return t;
}

nlohmann::json ranks_json(const std::vector<RankReport>& reports) {
  const RankTraffic t = rank_traffic(reports);
  nlohmann::json per_rank = nlohmann::json::array();
  for (std::size_t k = 0; k < reports.size(); ++k) {
    nlohmann::json e = nlohmann::json::parse(rank_report_json(reports[k]));
    // Totals over the rounds, to other ranks and from them.
    e["sent"] = t.sent_by_rank[k];
    e["received"] = t.received_by_rank[k];
    per_rank.push_back(std::move(e));
  }
  return {{"ranks", reports.size()},
          {"bytes_per_descriptor", std::uint64_t(DescriptorSet::kBytes)},
          {"descriptors_sent", t.sent},
          {"descriptors_received", t.received},
          {"bytes_sent", t.sent * std::uint64_t(DescriptorSet::kBytes)},
          {"exchange_balanced", t.balanced},
          {"per_rank", std::move(per_rank)},
          {"traffic_total", t.total},
          {"traffic", t.rounds}};
}

std::string rank_report_json(const RankReport& r) {
  nlohmann::json kernels = nlohmann::json::object();
  for (const auto& [name, s] : r.kernel_seconds) kernels[name] = s;
  nlohmann::json j = {{"rank", r.rank},
                      {"pes", {r.pe_begin, r.pe_end}},
                      {"host", r.host},
                      {"device", r.device},
                      {"device_bytes", r.device_bytes},
                      {"scene_bytes", r.scene_bytes},
                      {"host_peak_bytes", r.host_peak_bytes},
                      {"render_seconds", r.render_seconds},
                      {"mpi_seconds", r.mpi_seconds},
                      {"exchange_seconds", r.exchange_seconds},
                      {"exposed_seconds", r.exposed_seconds},
                      {"kernel_seconds", kernels},
                      {"sent", r.sent},
                      {"received", r.received}};
  if (r.share.active)  // a scene read in shares: what this rank read, held and spent on it
    j["share"] = {{"facets_read", r.share.facets_read},
                  {"facets_held", r.share.facets_held},
                  {"texture_bytes", r.share.texture_bytes},
                  {"read_seconds", r.share.read_seconds},
                  {"partition_seconds", r.share.partition_seconds},
                  {"exchange_seconds", r.share.exchange_seconds},
                  {"bank_seconds", r.share.bank_seconds},
                  {"pilot_facets_held", r.share.pilot_facets_held}};
  return j.dump();
}

RankReport rank_report_from_json(const std::string& text) {
  const nlohmann::json j = nlohmann::json::parse(text);
  RankReport r;
  r.rank = j.at("rank");
  r.pe_begin = j.at("pes").at(0);
  r.pe_end = j.at("pes").at(1);
  r.host = j.at("host");
  r.device = j.at("device");
  r.device_bytes = j.at("device_bytes");
  r.scene_bytes = j.at("scene_bytes");
  r.host_peak_bytes = j.at("host_peak_bytes");
  r.render_seconds = j.at("render_seconds");
  r.mpi_seconds = j.at("mpi_seconds");
  r.exchange_seconds = j.at("exchange_seconds");
  r.exposed_seconds = j.at("exposed_seconds");
  for (const auto& [name, s] : j.at("kernel_seconds").items()) r.kernel_seconds.emplace_back(name, s.get<double>());
  r.sent = j.at("sent").get<std::vector<std::vector<std::uint64_t>>>();
  r.received = j.at("received").get<std::vector<std::vector<std::uint64_t>>>();
  if (const auto s = j.find("share"); s != j.end()) {
    r.share.active = true;
    r.share.facets_read = s->at("facets_read");
    r.share.facets_held = s->at("facets_held");
    r.share.texture_bytes = s->at("texture_bytes");
    r.share.read_seconds = s->at("read_seconds");
    r.share.partition_seconds = s->at("partition_seconds");
    r.share.exchange_seconds = s->at("exchange_seconds");
    r.share.bank_seconds = s->at("bank_seconds");
    r.share.pilot_facets_held = s->at("pilot_facets_held");
  }
  return r;
}

}  // namespace opsila
