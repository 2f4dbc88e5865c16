// The --stats JSON: what a render did (rays, per-level/per-PE work, kernel
// launches, memory per bank, PE-to-PE traffic), for reports and benchmarks.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "machine/renderer.h"
#include "core/scene.h"

namespace opsila {

// Keys: version, device, width, height, depth, pes, bank_capacity, clusters,
// work_group_size, rounds, scene {triangles, facets, objects, lights},
// rays {primary, primary_hits, secondary, shadow, total}, render_seconds,
// mrays_per_s, levels [{level, totals{...}, pes[{...}]}],
// descriptors {spawned, finished, forwards, overflow_deferrals},
// balanced (spawned == finished), launches [{name, round, seconds}],
// launch_summary {name: {count, total_seconds}},
// memory {bank_bytes[], bank_bytes_max, bank_bytes_mean, global_bytes, replicated_bytes},
// traffic [level][src][dst]; with several MPI ranks, mpi {...} (ranks_json).
nlohmann::json stats_json(const RenderResult& result, const Scene& scene,
                          const RenderSettings& settings, const std::string& device_description);

// Several MPI ranks: per-rank reports, the rank x rank traffic of every
// round and in all, and whether every rank received what the others sent.
nlohmann::json ranks_json(const std::vector<RankReport>& reports);

// One rank's report as JSON text (ranks gather them as text) and back.
std::string rank_report_json(const RankReport& report);
RankReport rank_report_from_json(const std::string& text);

}  // namespace opsila
