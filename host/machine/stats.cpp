#include "machine/stats.h"

#include <algorithm>
#include <cstdint>
#include <map>

#include "opsila_shared.h"

namespace opsila {

namespace {

// JSON names of the OPSILA_STAT_* counters, by index.
const char* const kCounterNames[OPSILA_STAT_COUNT] = {
    "traced",          // OPSILA_STAT_TRACED
    "radiance",        // OPSILA_STAT_RADIANCE
    "resolved",        // OPSILA_STAT_RESOLVED
    "shadow",          // OPSILA_STAT_SHADOW
    "triangle_tests",  // OPSILA_STAT_TRI_TESTS
    "box_tests",       // OPSILA_STAT_BOX_TESTS
    "sphere_tests",    // OPSILA_STAT_SPHERE_TESTS
    "spawned_radiance",  // OPSILA_STAT_SPAWN_RADIANCE
    "spawned_shadow",    // OPSILA_STAT_SPAWN_SHADOW
    "misses",          // OPSILA_STAT_MISS
    "occluded",        // OPSILA_STAT_OCCLUDED
    "lit",             // OPSILA_STAT_LIT
    "forwards",        // OPSILA_STAT_FORWARD
    "route_tests",     // OPSILA_STAT_ROUTE_TESTS
};
static_assert(OPSILA_STAT_COUNT == 14, "update kCounterNames with the OPSILA_STAT_* list");

nlohmann::json counters_object(const std::vector<std::uint64_t>& values) {
  nlohmann::json out = nlohmann::json::object();
  for (int i = 0; i < OPSILA_STAT_COUNT; ++i)
    out[kCounterNames[i]] = i < static_cast<int>(values.size()) ? values[i] : 0;
  // Every ray that finishes at this level: shaded hits, misses, shadow rays.
  const auto at = [&](int i) -> std::uint64_t { return i < static_cast<int>(values.size()) ? values[i] : 0; };
  out["finished"] = at(OPSILA_STAT_RESOLVED) + at(OPSILA_STAT_MISS) + at(OPSILA_STAT_OCCLUDED) +
                    at(OPSILA_STAT_LIT);
  out["spawned"] = at(OPSILA_STAT_SPAWN_RADIANCE) + at(OPSILA_STAT_SPAWN_SHADOW);
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
    launches.push_back({{"name", launch.name}, {"round", launch.round}, {"seconds", launch.seconds}});
    auto& summary = by_name[launch.name];
    summary.first += 1;
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
  j["work_group_size"] = s.work_group_size;
  j["rounds"] = s.rounds;
  j["scene"] = {{"triangles", scene.triangles.size()},
                {"facets", scene.num_facets},
                {"objects", scene.num_objects},
                {"lights", scene.lights.size()}};

  const RayCounts& rays = result.rays;
  const std::uint64_t total_rays = rays.total();
  j["rays"] = {{"primary", rays.primary},
               {"primary_hits", rays.primary_hits},
               {"secondary", rays.secondary},
               {"shadow", rays.shadow},
               {"total", total_rays}};
  j["render_seconds"] = s.render_seconds;
  j["mrays_per_s"] = s.render_seconds > 0 ? static_cast<double>(total_rays) / s.render_seconds / 1e6 : 0.0;

  j["levels"] = levels_json(s);

  // Every descriptor created (primary hits and spawned rays; forwards only
  // move them between PEs) must finish exactly once: shaded, missed,
  // occluded or lit.
  j["descriptors"] = {{"spawned", s.descriptors_spawned},
                      {"finished", s.descriptors_finished},
                      {"forwards", s.forwards},
                      {"overflow_deferrals", s.overflow_deferrals}};
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

  j["traffic"] = traffic_json(s);
  return j;
}

}  // namespace opsila
