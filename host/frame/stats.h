// The --stats JSON: what a render did (rays, per-level/per-PE work, kernel
// launches, memory per bank, PE-to-PE traffic), for reports and benchmarks.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "scene/render_types.h"
#include "scene/scene.h"

namespace opsila {

// Keys: version, device, width, height, depth, pes, bank_capacity, clusters,
// work_group_size, bvh_nodes ("float" or "quantised"), rounds, scene {triangles, facets, objects, lights},
// rays {primary, primary_hits, secondary, shadow, total}, render_seconds,
// readback_seconds (of it, the image read back and decoded),
// prepare {read_seconds, parse_seconds, partition_seconds, bank_build_seconds,
// upload_seconds, pilot_seconds, peak_host_bytes} (prepare_json),
// mrays_per_s, levels [{level, totals{...}, pes[{...}]}],
// descriptors {spawned, finished, forwards, overflow_deferrals, waiting_peak,
//   throttled_rounds},
// balanced (spawned == finished), launches [{name, round, seconds, queued,
// started}] (queued and started: seconds after the frame's first enqueue,
// device clock; past
// Launcher::kRecordCap, one per kernel with round -2 and its "launches"),
// launch_summary {name: {count, total_seconds}},
// memory {bank_bytes[], bank_bytes_max, bank_bytes_mean, global_bytes, replicated_bytes},
// traffic [level][src][dst]; with several MPI ranks, mpi {...} (ranks_json).
// The bytes a triangle costs on this device and this host (--stats and the
// bench's "triangle_cost").
nlohmann::json triangle_cost_json(const RenderStats& s, std::size_t triangles);
nlohmann::json stats_json(const RenderResult& result, const Scene& scene,
                          const RenderSettings& settings, const std::string& device_description);

// The preparation's stages (core/stage_clock.h) as the --stats "prepare" section.
nlohmann::json prepare_json(const PrepareTimes& t);

// Several MPI ranks: the descriptors between ranks, from what each rank
// says it sent and received. A rank's own PEs count on the diagonal.
struct RankTraffic {
  std::vector<std::vector<std::vector<std::uint64_t>>> rounds;  // [round][from][to]
  std::vector<std::vector<std::uint64_t>> total;                // [from][to], all rounds
  std::vector<std::uint64_t> sent_by_rank, received_by_rank;    // to / from other ranks
  std::uint64_t sent = 0, received = 0;                         // between different ranks
  bool balanced = false;  // each rank received from each other what it was sent, round by round
};
RankTraffic rank_traffic(const std::vector<RankReport>& reports);

// The paper's occupancy of a render: the tests done (ray-box + ray-facet)
// over the tests the phases would have allowed had every PE been as busy as
// the busiest, level by level (as the bench reports it). 0 without work.
double test_occupancy(const RenderStats& st);

// Several MPI ranks: per-rank reports, the rank x rank traffic of every
// round and in all, and whether every rank received what the others sent.
nlohmann::json ranks_json(const std::vector<RankReport>& reports);

// One rank's report as JSON text (ranks gather them as text) and back.
std::string rank_report_json(const RankReport& report);
RankReport rank_report_from_json(const std::string& text);

}  // namespace opsila
