// The bench's --json file (keys in docs/BENCHMARKS.md).
#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include "bench/report.h"
#include "core/util.h"
#include "frame/stats.h"
#include "opsila_shared.h"

namespace opsila {

namespace {

using nlohmann::json;

json psnr_value(double p) { return std::isfinite(p) ? json(p) : json("inf"); }

json optional_value(const std::optional<double>& v) { return v ? json(*v) : json(nullptr); }

double fraction_of_copy(const ScatterPoint& p) {
  return p.copy_kernel_gbytes_per_s() > 0 ? p.gbytes_per_s() / p.copy_kernel_gbytes_per_s() : 0.0;
}

json spread_json(const Spread& s) { return {{"min", s.min}, {"median", s.median}, {"max", s.max}}; }

json context_json(const BenchReport& r) {
  const BenchContext& c = r.context;
  return {{"date", c.date},
          {"host_name", c.host_name},
          {"num_cpus", c.num_cpus},
          {"mhz_per_cpu", c.mhz_per_cpu},
          {"cpu_model", c.cpu_model},
          {"load_avg", {c.load_avg[0], c.load_avg[1], c.load_avg[2]}},
          {"library_build_type", c.build_type},
          {"opsila_version", OPSILA_VERSION},
          {"device", r.device.name},
          {"device_platform", r.device.platform},
          {"device_version", r.device.version},
          {"driver_version", r.device.driver_version}};
}

json header_json(const BenchReport& r) {
  const RenderStats& st = r.stats();
  json j;
  j["version"] = OPSILA_VERSION;
  j["device"] = r.device.description;
  j["device_info"] = {{"name", r.device.name},
                      {"platform", r.device.platform},
                      {"vendor", r.device.vendor},
                      {"version", r.device.version},
                      {"driver_version", r.device.driver_version},
                      {"is_gpu", r.device.is_gpu},
                      {"compute_units", r.device.compute_units},
                      {"global_mem_bytes", r.device.global_mem_bytes},
                      {"max_alloc_bytes", r.device.max_alloc_bytes}};
  j["host_threads"] = r.host_threads;
  j["host_load_average"] = {{"before", r.load_before}, {"after", r.load_after}};
  j["scene"] = {{"path", r.scene_path}, {"triangles", r.triangles}, {"facets", r.facets},
                {"objects", r.objects},  {"clusters", st.num_clusters}, {"lights", r.lights}};
  j["image"] = {{"width", r.width}, {"height", r.height}, {"pixels", std::size_t(r.width) * r.height}};
  j["depth"] = r.depth;
  j["spp"] = r.spp;
  j["pes"] = r.pes;
  j["routing"] = r.stats().routing == OPSILA_ROUTING_SPHERES ? "spheres" : "boxes";
  j["balance"] = balance_name(r.stats().balance);
  j["pilot_frames"] = r.stats().pilot_frames;
  j["pilot_seconds"] = r.stats().pilot_seconds;
  j["pilot_warm_up_seconds"] = r.stats().pilot_warm_up_seconds;
  j["bank_capacity"] = st.bank_capacity;
  j["work_group_size"] = st.work_group_size;
  j["bvh_nodes"] = st.quantised_nodes ? "quantised" : "float";
  j["settings"] = {{"repeats", r.repeats}, {"warmup", r.warmup}, {"host_repeats", r.host_repeats},
                   {"quick", r.quick},     {"scatter_max_log2", r.scatter_max_log2}};
  j["compile_seconds"] = r.compile_seconds;
  j["first_render_seconds"] = r.first_render_seconds;
  return j;
}

json levels_json(const BenchReport& r) {
  json levels = json::array();
  for (std::size_t l = 0; l < r.work.size(); ++l) {
    const LevelWork& w = r.work[l];
    levels.push_back({{"level", l},
                      {"descriptors", w.total_descriptors},
                      {"tests", w.total_tests},
                      {"triangle_tests", w.triangle_total},
                      {"box_tests", w.box_total},
                      {"sphere_tests", w.sphere_total},
                      {"spawned_radiance", w.spawned_radiance},
                      {"spawned_shadow", w.spawned_shadow},
                      {"forwards", w.forwards},
                      {"max_pe_descriptors", w.max_descriptors},
                      {"max_pe_tests", w.max_tests},
                      {"occupancy_descriptors", optional_value(occupancy_of(w.total_descriptors, w.max_descriptors,
                                                                            std::size_t(r.pes)))},
                      {"occupancy", optional_value(occupancy_of(w.total_tests, w.max_tests, std::size_t(r.pes)))}});
  }
  return levels;
}

json pe_json(const BenchReport& r) {
  const RenderStats& st = r.stats();
  json pe_list = json::array();
  for (int p = 0; p < r.pes; ++p) {
    std::uint64_t d = 0, t = 0, tri = 0, box = 0, sph = 0;
    std::vector<std::uint64_t> d_by, t_by;
    for (const LevelWork& w : r.work) {
      d += w.descriptors[p];
      t += w.tests[p];
      tri += w.tri_tests[p];
      box += w.box_tests[p];
      sph += w.sphere_tests[p];
      d_by.push_back(w.descriptors[p]);
      t_by.push_back(w.tests[p]);
    }
    pe_list.push_back({{"pe", p},
                       {"descriptors", d},
                       {"tests", t},
                       {"triangle_tests", tri},
                       {"box_tests", box},
                       {"sphere_tests", sph},
                       {"descriptors_by_level", d_by},
                       {"tests_by_level", t_by},
                       {"bank_bytes", p < static_cast<int>(st.bank_bytes.size()) ? st.bank_bytes[p] : 0}});
  }
  return pe_list;
}

json render_json(const BenchReport& r) {
  const RenderStats& st = r.stats();
  const double rs = st.render_seconds, seconds = r.render_seconds;
  json j;
  j["rays"] = r.rays_total();
  j["rays_by_kind"] = {{"primary", r.opsila.rays.primary}, {"secondary", r.opsila.rays.secondary}, {"shadow", r.opsila.rays.shadow}};
  j["seconds"] = seconds;
  j["seconds_all"] = r.render_times;
  j["seconds_spread"] = spread_json(spread_of(r.render_times));
  j["mrays_per_s"] = mrays(r.rays_total(), seconds);
  j["mrays_per_s_by_kind"] = {{"primary", mrays(r.opsila.rays.primary, seconds)},
                              {"secondary", mrays(r.opsila.rays.secondary, seconds)},
                              {"shadow", mrays(r.opsila.rays.shadow, seconds)}};
  j["deterministic"] = r.deterministic;
  j["rounds"] = st.rounds;
  j["phase_switches"] = 2 * st.rounds;
  j["kernel_seconds"] = r.kernel_seconds;
  j["exchange_seconds"] = r.exchange_seconds;
  j["exchange_share"] = r.exchange_share;
  j["overhead_seconds"] = r.overhead_seconds;
  j["overhead_share"] = r.overhead_share;
  j["readback_seconds"] = st.readback_seconds;  // part of the overhead: the image read back and decoded
  j["idle_seconds"] = r.idle_seconds;            // part of it: the device idle between kernels,
  j["host_late_seconds"] = r.host_late_seconds;  // of which before the host had enqueued the next
  j["exchange_plus_overhead_share"] = r.exchange_share + r.overhead_share;
  j["descriptors"] = {{"spawned", st.descriptors_spawned},
                      {"finished", st.descriptors_finished},
                      {"forwards", st.forwards},
                      {"overflow_deferrals", st.overflow_deferrals}};
  json tk = json::object();
  for (const auto& [name, e] : r.by_kernel)
    tk[name] = {{"launches", e.launches}, {"seconds", e.seconds}, {"mode", launch_mode(name)},
                {"share", rs > 0 ? e.seconds / rs : 0.0}};
  j["time_by_kernel"] = tk;
  j["launches_per_frame"] = r.launches_per_frame;
  json phases = json::array();
  for (const LaunchRecord& l : st.launches)
    phases.push_back({{"name", l.name}, {"mode", launch_mode(l.name)}, {"round", l.round}, {"seconds", l.seconds}});
  j["phases"] = std::move(phases);
  j["levels"] = levels_json(r);
  j["pe"] = pe_json(r);
  j["work"] = {{"descriptors", r.all_descriptors},
               {"triangle_tests", r.all_triangle_tests},
               {"box_tests", r.all_box_tests},
               {"sphere_tests", r.all_sphere_tests},
               {"route_tests", r.all_route_tests},
               {"routing_tests", r.all_sphere_tests + r.all_route_tests},
               {"tests", r.all_triangle_tests + r.all_box_tests}};
  j["occupancy"] = optional_value(r.occupancy);
  j["occupancy_descriptors"] = optional_value(r.occupancy_descriptors);
  json traffic = json::array();
  const std::size_t P = std::size_t(r.pes);
  for (const auto& flat : st.traffic) {
    json m = json::array();
    for (std::size_t s = 0; s < P; ++s)
      m.push_back(std::vector<std::uint64_t>(flat.begin() + s * P, flat.begin() + (s + 1) * P));
    traffic.push_back(std::move(m));
  }
  j["traffic"] = std::move(traffic);
  return j;
}

// One point of the curve, every figure.
json scatter_point_json(const ScatterPoint& p) {
  return {{"length", p.length},
          {"moved", p.moved},
          {"waiting", p.waiting},
          {"pes", p.pes},
          {"bank_capacity", p.n},
          {"repeats", p.repeats},
          {"bytes", p.bytes()},
          {"host_seconds", p.host_seconds},
          {"kernel_seconds", p.kernel_seconds},
          {"kernels", {{"scatter_count", p.count_seconds},
                       {"scatter_plan", p.plan_seconds},
                       {"scatter_move", p.move_seconds}}},
          {"speedup", p.speedup()},
          {"gbytes_per_s", p.gbytes_per_s()},
          {"host_gbytes_per_s", p.host_gbytes_per_s()},
          {"copy_kernel_seconds", p.copy_kernel_seconds},
          {"copy_kernel_gbytes_per_s", p.copy_kernel_gbytes_per_s()},
          {"copy_buffer_seconds", p.copy_buffer_seconds},
          {"copy_buffer_gbytes_per_s", p.copy_buffer_gbytes_per_s()},
          {"fraction_of_copy", fraction_of_copy(p)},
          {"six_vectors_seconds", p.six_vectors_seconds},
          {"six_vectors_gbytes_per_s", p.six_vectors_gbytes_per_s()},
          {"one_record_seconds", p.one_record_seconds},
          {"one_record_gbytes_per_s", p.one_record_gbytes_per_s()},
          {"verified", p.verified},
          {"host_seconds_spread", spread_json(p.host_spread)},
          {"kernel_seconds_spread", spread_json(p.kernel_spread)},
          {"copy_kernel_seconds_spread", spread_json(p.copy_kernel_spread)},
          {"copy_buffer_seconds_spread", spread_json(p.copy_buffer_spread)},
          {"six_vectors_seconds_spread", spread_json(p.six_vectors_spread)},
          {"one_record_seconds_spread", spread_json(p.one_record_spread)}};
}

json scatter_json(const std::vector<ScatterPoint>& curve) {
  json scatter = json::array();
  for (const ScatterPoint& p : curve) scatter.push_back(scatter_point_json(p));
  return scatter;
}

// One length over several PE counts: of each point, the figures that
// compare the counts.
json scatter_by_pes_json(const std::vector<ScatterPoint>& by_pes) {
  json sp = json::array();
  for (const ScatterPoint& p : by_pes) {
    const json all = scatter_point_json(p);
    json row;
    for (const char* key : {"pes", "length", "kernel_seconds", "host_seconds", "speedup", "gbytes_per_s",
                            "host_gbytes_per_s", "copy_kernel_gbytes_per_s", "fraction_of_copy", "verified",
                            "host_seconds_spread", "kernel_seconds_spread"})
      row[key] = all.at(key);
    sp.push_back(std::move(row));
  }
  return sp;
}

json memory_json(const BenchReport& r) {
  const RenderStats& st = r.stats();
  // Texture maps: each bank holds the maps its facets use (part of bank_bytes).
  std::uint64_t texture_max = 0, texture_sum = 0;
  for (std::uint64_t b : st.texture_bytes) texture_max = std::max(texture_max, b), texture_sum += b;
  return {{"bank_bytes", st.bank_bytes},
          {"texture_bytes", st.texture_bytes},
          {"texture_bytes_max", texture_max},
          {"texture_bytes_all_banks", texture_sum},
          {"texture_replicated_bytes", st.texture_replicated_bytes},
          {"bank_bytes_max", r.bank_max},
          {"bank_bytes_mean", r.bank_mean},
          {"global_bytes", st.global_bytes},
          {"replicated_bytes", st.replicated_bytes},
          {"per_pe_bytes_max", r.bank_max + st.global_bytes},
          {"replicated_over_bank_max", r.replicated_over_bank_max()},
          {"all_pes_distributed_bytes", r.bank_sum + std::uint64_t(r.pes) * st.global_bytes},
          {"all_pes_replicated_bytes", std::uint64_t(r.pes) * st.replicated_bytes}};
}

// OPSILA's preparation stage by stage, beside the baselines' builds.
json prepare_bench_json(const BenchReport& r) {
  json j = prepare_json(r.stats().prepare);
  j["seconds"] = r.prepare_seconds();
  const double embree = r.embree.present ? r.embree.median_run.build_seconds : 0.0;
  j["embree_build_seconds"] = r.embree.present ? json(embree) : json(nullptr);
  j["megakernel_build_seconds"] = r.megakernel.present ? json(r.megakernel.median_run.build_seconds) : json(nullptr);
  j["vs_embree_build"] = embree > 0 ? json(r.prepare_seconds() / embree) : json(nullptr);
  return j;
}

json baselines_json(const BenchReport& r) {
  const RenderStats& st = r.stats();
  json baselines = json::object();
  for (const BaselineRun* b : r.baselines()) {
    const BaselineImage& img = b->median_run;
    const Agreement g = compare_images(img.rgb, r.opsila.rgb);
    const bool same_rays = img.rays.same_rays(r.opsila.rays);
    json e = {{"label", b->label},
              {"seconds", b->seconds},
              {"seconds_all", b->seconds_all},
              {"seconds_spread", spread_json(spread_of(b->seconds_all))},
              {"build_seconds", img.build_seconds},
              {"rays", img.rays.total()},
              {"rays_by_kind", {{"primary", img.rays.primary}, {"secondary", img.rays.secondary},
                                {"shadow", img.rays.shadow}}},
              {"mrays_per_s", mrays(img.rays.total(), b->seconds)},
              {"rays_match_opsila", same_rays},
              {"psnr_vs_opsila", psnr_value(g.psnr)},
              {"max_abs_diff_vs_opsila", g.max_abs_diff},
              {"identical_pixels_vs_opsila", g.identical_pixels}};
    if (b->threads > 0) e["threads"] = b->threads;
    if (b->name == "replicated_megakernel") {
      e["kernel_seconds"] = b->kernel_seconds;
      e["kernel_seconds_spread"] = spread_json(spread_of(b->kernel_seconds_all));
      e["device"] = r.device.description;
      e["scene_bytes_per_work_item"] = st.replicated_bytes;
      e["triangle_tests"] = img.triangle_tests;
      e["box_tests"] = img.box_tests;
      e["tests"] = img.triangle_tests + img.box_tests;
    }
    if (b->name == "embree") e["version"] = embree_version();
    baselines[b->name] = std::move(e);
  }
  return baselines;
}

// The traversal alone (null when not measured), and each render's seconds
// per ray over its seconds per ray.
json traversal_json(const BenchReport& r) {
  const TraversalAlone& t = r.traversal;
  if (!t.present) return nullptr;
  const BaselineImage& mk = r.megakernel.median_run;
  return {{"bvh", "megakernel"},
          {"seconds", t.seconds},
          {"seconds_all", t.seconds_all},
          {"seconds_spread", spread_json(spread_of(t.seconds_all))},
          {"rays", t.rays()},
          {"nearest_rays", t.nearest_rays},
          {"any_rays", t.any_rays},
          {"nearest_seconds", t.nearest_seconds},
          {"any_seconds", t.any_seconds},
          {"mrays_per_s", mrays(t.rays(), t.seconds)},
          {"rays_match_megakernel", t.rays() == mk.rays.total()},
          {"megakernel_kernels_over_traversal", optional_value(r.over_traversal(r.megakernel.kernel_seconds,
                                                                                mk.rays.total()))},
          {"megakernel_over_traversal", optional_value(r.over_traversal(r.megakernel.seconds, mk.rays.total()))},
          {"opsila_over_traversal", optional_value(r.over_traversal(r.render_seconds, r.rays_total()))}};
}

// Cycles by stage of the SPMD phase and of the megakernel (null where they
// were not counted, with the reason in "stages_skipped").
json stages_json(const BenchReport& r) {
  auto kernel = [](const std::vector<std::uint64_t>& cycles, double seconds, double clocked) -> json {
    if (cycles.empty()) return nullptr;
    json j = json::object();
    StageClockCost cost;
    for (const StageTime& s : stage_times(cycles, seconds, clocked, &cost))
      j[s.name] = {{"cycles", s.cycles},   {"clock_readings", s.entries}, {"share", s.share},
                   {"raw_share", s.raw_share}, {"seconds", s.seconds}};
    return {{"stages", j},
            {"clocked_over_timed", seconds > 0 ? clocked / seconds : 0.0},
            {"cycles_per_clock_reading", cost.cycles_per_entry}};
  };
  const auto spmd = r.by_kernel.find("spmd_phase");
  const double spmd_seconds = spmd == r.by_kernel.end() ? 0.0 : spmd->second.seconds;
  return {{"spmd_phase", kernel(r.spmd_stage_cycles, spmd_seconds, r.spmd_clocked_seconds)},
          {"megakernel", kernel(r.megakernel_stage_cycles, r.megakernel.kernel_seconds, r.megakernel_clocked_seconds)}};
}

// Several MPI ranks: the --stats "mpi" section (per-rank reports, the rank x
// rank traffic) and what the exchange between ranks costs.
json mpi_json(const BenchReport& r) {
  const RankFigures f = rank_figures(r);
  json j = ranks_json(r.stats().ranks);
  j["frame_seconds_slowest_rank"] = f.frame_seconds;
  j["exchange_share"] = f.exchange_share;
  j["exposed_share"] = f.exposed_share;
  j["mpi_share"] = f.mpi_share;
  j["exchange_seconds_per_descriptor"] = f.seconds_per_descriptor;
  j["exchange_seconds_per_ray"] = f.seconds_per_ray;
  j["descriptors_between_ranks_per_ray"] = f.descriptors_per_ray;
  j["descriptors_between_ranks_by_level"] = r.cross_rank_by_level;
  return j;
}

// Targets (benchmarks, reported, never enforced).
json targets_json(const BenchReport& r) {
  json targets = json::object();
  const ScatterPoint* p20 = nullptr;
  for (const ScatterPoint& p : r.curve)
    if (p.length == (std::size_t(1) << 20)) p20 = &p;
  if (p20)
    targets["scatter_2p20_vs_copy"] = {
        {"gbytes_per_s", p20->gbytes_per_s()},
        {"copy_gbytes_per_s", p20->copy_kernel_gbytes_per_s()},
        {"fraction", p20->gbytes_per_s() / std::max(1e-30, p20->copy_kernel_gbytes_per_s())},
        {"goal", 0.75},
        {"met", p20->gbytes_per_s() >= 0.75 * p20->copy_kernel_gbytes_per_s()}};
  else
    targets["scatter_2p20_vs_copy"] = nullptr;
  const double share = r.exchange_share + r.overhead_share;
  targets["exchange_plus_overhead"] = {{"share", share}, {"goal", 0.10}, {"met", share < 0.10}};
  targets["occupancy"] = {{"occupancy", optional_value(r.occupancy)},
                          {"goal", 0.6},
                          {"met", r.occupancy.has_value() && *r.occupancy >= 0.6}};
  targets["rounds"] = {{"rounds", r.stats().rounds}, {"goal", 60}, {"met", r.stats().rounds <= 60}};
  if (!r.megakernel.present) {
    targets["opsila_vs_megakernel"] = nullptr;  // not measured (several MPI ranks)
  } else {
    const double mega = mrays(r.megakernel.median_run.rays.total(), r.megakernel.seconds);
    const double mine = mrays(r.rays_total(), r.render_seconds);
    targets["opsila_vs_megakernel"] = {{"ratio", mega > 0 ? mine / mega : 0.0},
                                       {"goal", 0.7},
                                       {"met", mega > 0 && mine >= 0.7 * mega}};
  }
  if (r.embree.present) {
    const double e = mrays(r.embree.median_run.rays.total(), r.embree.seconds);
    const double mine = mrays(r.rays_total(), r.render_seconds);
    targets["opsila_vs_embree"] = {{"opsila_mrays_per_s", mine},
                                   {"embree_mrays_per_s", e},
                                   {"ratio", e > 0 ? mine / e : 0.0},
                                   {"goal", 0.3},
                                   {"met", e > 0 && mine >= 0.3 * e}};
    const double mk = mrays(r.megakernel.median_run.rays.total(), r.megakernel.seconds);
    targets["megakernel_vs_embree"] = {{"megakernel_mrays_per_s", mk},
                                       {"embree_mrays_per_s", e},
                                       {"ratio", e > 0 ? mk / e : 0.0},
                                       {"goal", 0.45},
                                       {"met", e > 0 && mk >= 0.45 * e}};
  } else {
    targets["opsila_vs_embree"] = nullptr;
    targets["megakernel_vs_embree"] = nullptr;
  }
  return targets;
}

}  // namespace

nlohmann::json bench_json(const BenchReport& r) {
  json j = header_json(r);
  j["context"] = context_json(r);
  j["render"] = render_json(r);
  j["ranks"] = r.ranks;
  if (r.ranks > 1) j["mpi"] = mpi_json(r);
  // With several ranks the scatter curve is not measured (a single-device figure).
  j["scatter"] = scatter_json(r.curve);
  j["scatter_limit"] = r.scatter_limit.empty() ? json(nullptr) : json(r.scatter_limit);
  j["scatter_by_pes"] = scatter_by_pes_json(r.by_pes);
  // The copy ceiling: the longest vector's copy bandwidth (the asymptote).
  j["copy_gbytes_per_s"] = r.curve.empty() ? json(nullptr) : json(r.curve.back().copy_kernel_gbytes_per_s());
  j["copy_buffer_gbytes_per_s"] = r.curve.empty() ? json(nullptr) : json(r.curve.back().copy_buffer_gbytes_per_s());
  j["bytes_per_descriptor"] = DescriptorSet::kBytes;
  j["memory"] = memory_json(r);
  j["triangle_cost"] = triangle_cost_json(r.stats(), r.triangles);
  j["prepare"] = prepare_bench_json(r);
  j["baselines"] = baselines_json(r);
  j["baselines_left_out"] = r.single_process_only.empty() ? json(nullptr) : json(r.single_process_only);
  j["traversal_alone"] = traversal_json(r);
  j["stages"] = stages_json(r);
  j["stages_skipped"] = r.stages_skipped.empty() ? json(nullptr) : json(r.stages_skipped);
  j["targets"] = targets_json(r);
  return j;
}

}  // namespace opsila
