// The bench's summary on stdout: renders side by side, work, phases,
// occupancy, memory and the scatter curve.
#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <string>

#include "bench/report.h"
#include "core/util.h"

namespace opsila {

namespace {

void appendf(std::string& out, const char* fmt, ...) __attribute__((format(printf, 2, 3)));
void appendf(std::string& out, const char* fmt, ...) {
  char line[1024];
  va_list ap;
  va_start(ap, fmt);
  std::vsnprintf(line, sizeof line, fmt, ap);
  va_end(ap);
  out += line;
}

using ull = unsigned long long;

std::string bench_bytes(double bytes) {
  return bytes < 1024.0 * 1024 ? format_bytes(bytes, 1, 1) : format_bytes(bytes, 2, 1);
}

double percent_of_copy(const ScatterPoint& p) {
  return p.copy_kernel_gbytes_per_s() > 0 ? 100.0 * p.gbytes_per_s() / p.copy_kernel_gbytes_per_s() : 0.0;
}

void header_text(std::string& out, const BenchReport& r) {
  const RenderStats& st = r.stats();
  appendf(out, "opsila bench: %s, %dx%d, %d spp, depth %d, %d PEs (bank capacity %d, work-group %zu, balance %s)\n",
          r.scene_path.c_str(), r.width, r.height, r.spp, r.depth, r.pes, st.bank_capacity, st.work_group_size,
          balance_name(st.balance));
  if (st.balance == Balance::measured)
    appendf(out,
            "balance measured: the partition of the best of %d pilot frames, %.2f s while preparing (not timed; "
            "their first frame run once before them, %.2f s, as the timed frames' warm-up)\n",
            st.pilot_frames, st.pilot_seconds, st.pilot_warm_up_seconds);
  if (r.ranks > 1)
    appendf(out, "device: %d MPI ranks, one device each (below); rank 0: %s\n", r.ranks, r.device.description.c_str());
  else
    appendf(out, "device: %s\n", r.device.description.c_str());
  appendf(out, "scene: %zu triangles, %d facets, %d objects, %d clusters, %zu lights\n", r.triangles, r.facets,
          r.objects, st.num_clusters, r.lights);
  if (r.megakernel.present)
    appendf(out,
            "timing: median of %d rounds after %d warm-up, each round one frame of every renderer on the same rays "
            "in turn (host references: median of %d); compile %.2f s, not timed\n\n",
            r.repeats, r.warmup, r.host_repeats, r.compile_seconds);
  else
    appendf(out, "timing: median of %d runs after %d warm-up; compile %.2f s, not timed\n\n", r.repeats, r.warmup,
            r.compile_seconds);
}

void renders_text(std::string& out, const BenchReport& r) {
  auto ratio = [&](double m) {
    char text[32] = "-";
    if (const auto v = r.vs_embree(m)) std::snprintf(text, sizeof text, "%.2fx", *v);
    return std::string(text);
  };
  appendf(out, "%-40s %10s %10s %12s %10s %10s\n", "render (same rays)", "seconds", "Mrays/s", "rays", "PSNR dB",
          "vs Embree");
  const double own = mrays(r.rays_total(), r.render_seconds);
  appendf(out, "%-40s %10.4f %10.3f %12llu %10s %10s\n", ("OPSILA, " + std::to_string(r.pes) + " PEs").c_str(),
          r.render_seconds, own, ull(r.rays_total()), "-", ratio(own).c_str());
  for (const BaselineRun* b : r.baselines()) {
    const Agreement g = compare_images(b->median_run.rgb, r.opsila.rgb);
    char ps[32];
    if (std::isfinite(g.psnr))
      std::snprintf(ps, sizeof ps, "%.1f", g.psnr);
    else
      std::snprintf(ps, sizeof ps, "inf");
    const double m = mrays(b->median_run.rays.total(), b->seconds);
    appendf(out, "%-40s %10.4f %10.3f %12llu %10s %10s\n", b->label.c_str(), b->seconds, m,
            ull(b->median_run.rays.total()), ps, ratio(m).c_str());
  }
  appendf(out, "work: OPSILA %llu descriptors, %llu ray-facet + %llu ray-box tests, %llu sphere tests\n",
          ull(r.all_descriptors), ull(r.all_triangle_tests), ull(r.all_box_tests), ull(r.all_sphere_tests));
  if (r.megakernel.present)
    appendf(out, "      megakernel %llu ray-facet + %llu ray-box tests\n", ull(r.megakernel.median_run.triangle_tests),
            ull(r.megakernel.median_run.box_tests));
  appendf(out, "routing (%s): %llu destination tests (%llu sphere + %llu PE-box/routing-node), %llu descriptors\n",
          r.stats().routing == OPSILA_ROUTING_SPHERES ? "spheres" : "boxes",
          ull(r.all_sphere_tests + r.all_route_tests), ull(r.all_sphere_tests), ull(r.all_route_tests),
          ull(r.all_descriptors));
  appendf(out, "rays: %llu primary, %llu secondary, %llu shadow\n\n", ull(r.opsila.rays.primary), ull(r.opsila.rays.secondary),
          ull(r.opsila.rays.shadow));
}

// The traversal alone, and each render's time per ray beside it.
void traversal_text(std::string& out, const BenchReport& r) {
  const TraversalAlone& t = r.traversal;
  if (!r.megakernel.present) return;
  if (!t.present) {
    appendf(out, "traversal alone: not measured (%s)\n\n", t.skipped.c_str());
    return;
  }
  appendf(out, "traversal alone (the megakernel's BVH and rays, nothing else): %.4f s, %.3f Mrays/s "
               "(nearest hit %zu rays %.4f s, any hit %zu rays %.4f s)\n",
          t.seconds, mrays(t.rays(), t.seconds), t.nearest_rays, t.nearest_seconds, t.any_rays, t.any_seconds);
  const double ns = 1e9 * t.seconds / double(std::max<std::size_t>(t.rays(), 1));
  auto per_ray = [&](const char* what, double seconds, std::uint64_t rays) {
    const auto x = r.over_traversal(seconds, rays);
    if (!x) return;
    // Below 1x (a renderer that proves rays miss without tracing them) the
    // rest is a saving: "traversal 5.4 - 1.2".
    const double rest = ns * (*x - 1);
    appendf(out, "  %-34s %8.1f ns per ray = traversal %.1f %c %.1f (%.2fx)\n", what, ns * *x, ns, rest < 0 ? '-' : '+',
            std::abs(rest), *x);
  };
  per_ray("megakernel, kernels", r.megakernel.kernel_seconds, r.megakernel.median_run.rays.total());
  per_ray("megakernel, frame", r.megakernel.seconds, r.megakernel.median_run.rays.total());
  per_ray("OPSILA, frame", r.render_seconds, r.rays_total());
  appendf(out, "\n");
}

// Where the SPMD phase's and the megakernel's time goes, stage by stage.
void stages_text(std::string& out, const BenchReport& r) {
  if (!r.stages_skipped.empty()) {
    appendf(out, "cycles by stage: not counted (%s)\n\n", r.stages_skipped.c_str());
    return;
  }
  auto line = [&](const char* what, const std::vector<std::uint64_t>& cycles, double timed, double clocked) {
    if (cycles.empty()) return;
    StageClockCost cost;
    const std::vector<StageTime> stages = stage_times(cycles, timed, clocked, &cost);
    appendf(out, "  %-12s", what);
    for (const StageTime& s : stages) appendf(out, " %s %.1f%%", s.name.c_str(), 100 * s.share);
    appendf(out, "\n  %-12s as counted:", "");
    for (const StageTime& s : stages) appendf(out, " %s %.1f%%", s.name.c_str(), 100 * s.raw_share);
    appendf(out, " (clocked frame %.2fx the timed: %.0f cycles a reading)\n", timed > 0 ? clocked / timed : 0.0,
            cost.cycles_per_entry);
  };
  appendf(out,
          "cycles by stage (clocked frames of each, as many as the timed ones, the median kept; counted by the\n"
          "processor's clock, the readings' own cost, the clocked frame's time beyond the timed one's, taken\n"
          "from the stages they entered):\n");
  const auto spmd = r.by_kernel.find("spmd_phase");
  line("SPMD phase", r.spmd_stage_cycles, spmd == r.by_kernel.end() ? 0.0 : spmd->second.seconds,
       r.spmd_clocked_seconds);
  line("megakernel", r.megakernel_stage_cycles, r.megakernel.kernel_seconds, r.megakernel_clocked_seconds);
  appendf(out, "\n");
}

// OPSILA's preparation beside the baselines' builds of the same scene.
void prepare_text(std::string& out, const BenchReport& r) {
  const PrepareTimes& t = r.stats().prepare;
  appendf(out, "preparation: OPSILA %.2f s (read %.2f, parse %.2f, partition %.2f, bank BVHs %.2f, upload %.2f",
          r.prepare_seconds(), t[PrepareStage::read], t[PrepareStage::parse], t[PrepareStage::partition],
          t[PrepareStage::bank_build], t[PrepareStage::upload]);
  if (t[PrepareStage::pilots] > 0) appendf(out, "; pilot frames %.2f apart", t[PrepareStage::pilots]);
  const double per = r.triangles ? 1.0 / double(r.triangles) : 0.0;
  appendf(out, "), peak host memory %s (%.0f B a triangle), device memory %s (%.0f B a triangle)\n",
          bench_bytes(double(t.peak_host_bytes)).c_str(), double(t.peak_host_bytes) * per,
          bench_bytes(double(r.stats().device_bytes)).c_str(), double(r.stats().device_bytes) * per);
  if (r.embree.present) {
    const double e = r.embree.median_run.build_seconds;
    appendf(out, "             Embree BVH build %.2f s", e);
    if (e > 0) appendf(out, " (OPSILA %.2fx)", r.prepare_seconds() / e);
    appendf(out, "\n");
  }
  if (r.megakernel.present)
    appendf(out, "             megakernel BVH build (one bank) %.2f s\n", r.megakernel.median_run.build_seconds);
  appendf(out, "\n");
}

void phases_text(std::string& out, const BenchReport& r) {
  const RenderStats& st = r.stats();
  const double rs = st.render_seconds;
  appendf(out, "phases: %d rounds (%d phase switches), render %.4f s%s\n", st.rounds, 2 * st.rounds, rs,
          r.ranks > 1 ? " (kernel times: rank 0's device)" : "");
  appendf(out, "  %-18s %5s %9s %10s %7s\n", "kernel", "mode", "launches", "seconds", "share");
  for (const auto& [name, e] : r.by_kernel)
    appendf(out, "  %-18s %5s %9d %10.4f %6.1f%%\n", name.c_str(), launch_mode(name), e.launches, e.seconds,
            rs > 0 ? 100.0 * e.seconds / rs : 0.0);
  appendf(out, "  %-18s %5s %9d\n", "all kernels", "", r.launches_per_frame);
  appendf(out, "  %-18s %5s %9s %10.4f %6.1f%%\n", "launch overhead", "", "", r.overhead_seconds,
          100.0 * r.overhead_share);
  appendf(out, "  %-18s %5s %9s %10.4f %6.1f%%  (host: the image read back and decoded)\n", "  of it: read-back", "",
          "", st.readback_seconds, rs > 0 ? 100.0 * st.readback_seconds / rs : 0.0);
  appendf(out, "  %-18s %5s %9s %10.4f %6.1f%%  (device idle between kernels: %.4f s before the host enqueued "
          "the next, %.4f s from enqueue to start)\n", "  of it: idle", "", "", r.idle_seconds,
          rs > 0 ? 100.0 * r.idle_seconds / rs : 0.0, r.host_late_seconds, r.idle_seconds - r.host_late_seconds);
  appendf(out, "  exchange (scatter) %.1f%% + launch overhead %.1f%% = %.1f%% of the frame\n\n",
          100.0 * r.exchange_share, 100.0 * r.overhead_share, 100.0 * (r.exchange_share + r.overhead_share));
}

void occupancy_text(std::string& out, const BenchReport& r) {
  appendf(out, "occupancy (mean/max per PE; work = ray-facet + ray-box tests):\n");
  appendf(out, "  %5s %12s %14s %12s %12s\n", "level", "descriptors", "tests", "occ(desc)", "occ(tests)");
  for (std::size_t l = 0; l < r.work.size(); ++l) {
    const LevelWork& w = r.work[l];
    if (w.total_descriptors == 0) continue;
    appendf(out, "  %5zu %12llu %14llu %12.3f %12.3f\n", l, ull(w.total_descriptors), ull(w.total_tests),
            occupancy_of(w.total_descriptors, w.max_descriptors, std::size_t(r.pes)).value_or(0.0),
            occupancy_of(w.total_tests, w.max_tests, std::size_t(r.pes)).value_or(0.0));
  }
  appendf(out, "  overall: %.3f (tests), %.3f (descriptors)\n\n", r.occupancy.value_or(0.0),
          r.occupancy_descriptors.value_or(0.0));
}

void memory_text(std::string& out, const BenchReport& r) {
  const RenderStats& st = r.stats();
  appendf(out, "memory: bank max %s, mean %s, + %s known to every PE; a replicated scene costs %s per PE (%.1fx)\n\n",
          bench_bytes(double(r.bank_max)).c_str(), bench_bytes(r.bank_mean).c_str(),
          bench_bytes(double(st.global_bytes)).c_str(), bench_bytes(double(st.replicated_bytes)).c_str(),
          r.replicated_over_bank_max());
  if (st.texture_replicated_bytes > 0) {
    std::uint64_t texture_max = 0, texture_sum = 0;
    for (std::uint64_t b : st.texture_bytes) texture_max = std::max(texture_max, b), texture_sum += b;
    appendf(out, "textures: bank max %s, all banks %s; one copy of every map %s\n\n",
            bench_bytes(double(texture_max)).c_str(), bench_bytes(double(texture_sum)).c_str(),
            bench_bytes(double(st.texture_replicated_bytes)).c_str());
  }
}

// A scene read in shares: what each rank read, held and spent preparing it
// (frame times and host peaks are in the table above).
void shares_text(std::string& out, const std::vector<RankReport>& ranks) {
  if (!ranks.front().share.active) return;
  appendf(out, "  scene read in shares (textures: texels the rank decoded; seconds: reading the share, partition, "
          "facet exchange, bank build; pilots: the most facets held while the pilot frames ran):\n");
  appendf(out, "  %4s %12s %12s %10s %9s %11s %10s %9s %12s\n", "rank", "facets read", "facets held", "textures",
          "read s", "partition s", "exchange s", "banks s", "pilots");
  for (const RankReport& k : ranks)
    appendf(out, "  %4d %12llu %12llu %10s %9.4f %11.4f %10.4f %9.4f %12llu\n", k.rank, ull(k.share.facets_read),
            ull(k.share.facets_held), bench_bytes(double(k.share.texture_bytes)).c_str(), k.share.read_seconds,
            k.share.partition_seconds, k.share.exchange_seconds, k.share.bank_seconds,
            ull(k.share.pilot_facets_held));
}

// Several MPI ranks: what each did, the rank x rank traffic, and what the
// exchange between ranks costs.
void ranks_text(std::string& out, const BenchReport& r) {
  const std::vector<RankReport>& ranks = r.stats().ranks;
  if (ranks.empty()) return;
  const RankFigures f = rank_figures(r);
  appendf(out, "MPI ranks: %d (the median run; exchange = read-back + MPI + write-back, exposed = not hidden "
          "by the SPMD phase)\n", r.ranks);
  appendf(out, "  %4s %7s %10s %10s %10s %9s %9s %9s %9s %10s %10s\n", "rank", "PEs", "device", "scene",
          "host peak", "frame s", "exch. s", "exposed s", "MPI s", "sent", "received");
  for (const RankReport& k : ranks) {
    const std::string pes = std::to_string(k.pe_begin) + ".." + std::to_string(k.pe_end - 1);
    appendf(out, "  %4d %7s %10s %10s %10s %9.4f %9.4f %9.4f %9.4f %10llu %10llu\n", k.rank, pes.c_str(),
            bench_bytes(double(k.device_bytes)).c_str(), bench_bytes(double(k.scene_bytes)).c_str(),
            bench_bytes(double(k.host_peak_bytes)).c_str(), k.render_seconds, k.exchange_seconds,
            k.exposed_seconds, k.mpi_seconds, ull(f.traffic.sent_by_rank[std::size_t(k.rank)]),
            ull(f.traffic.received_by_rank[std::size_t(k.rank)]));
  }
  shares_text(out, ranks);
  appendf(out, "  descriptors between ranks (row: from, column: to), all rounds:\n");
  for (std::size_t src = 0; src < f.traffic.total.size(); ++src) {
    appendf(out, "    %2zu:", src);
    for (std::uint64_t n : f.traffic.total[src]) appendf(out, " %10llu", ull(n));
    appendf(out, "\n");
  }
  appendf(out, "  %llu descriptors (%s) crossed ranks in %d rounds, %.4f per ray; every one received: %s\n",
          ull(f.traffic.sent), bench_bytes(double(f.traffic.sent) * double(DescriptorSet::kBytes)).c_str(),
          r.stats().rounds, f.descriptors_per_ray, f.traffic.balanced ? "yes" : "NO");
  if (!r.cross_rank_by_level.empty()) {
    appendf(out, "  by level (descriptors sent from one rank's PEs to another's):");
    for (std::size_t l = 0; l < r.cross_rank_by_level.size(); ++l)
      if (r.cross_rank_by_level[l] > 0) appendf(out, " %zu: %llu", l, ull(r.cross_rank_by_level[l]));
    appendf(out, "\n");
  }
  appendf(out, "  exchange between ranks: %.1f%% of the frame (%.1f%% exposed, %.1f%% in MPI calls), "
          "%.2f us per descriptor sent, %.3f us per ray (slowest rank)\n",
          100.0 * f.exchange_share, 100.0 * f.exposed_share, 100.0 * f.mpi_share, 1e6 * f.seconds_per_descriptor,
          1e6 * f.seconds_per_ray);
  appendf(out, "  not measured: %s\n\n", r.single_process_only.c_str());
}

void scatter_text(std::string& out, const BenchReport& r) {
  if (r.curve.empty()) return;
  appendf(out, "scatter (%d PEs, %zu bytes per descriptor, read + written):\n", r.scatter_pes, DescriptorSet::kBytes);
  appendf(out, "  %8s %11s %11s %8s %9s %9s %9s %7s %9s %9s\n", "length", "host ms", "kernel ms", "speedup", "GB/s",
          "copy GB/s", "cpbuf GB/s", "%copy", "6vec GB/s", "rec GB/s");
  for (const ScatterPoint& p : r.curve)
    appendf(out, "  %8s %11.4f %11.4f %8.2f %9.2f %9.2f %9.2f %6.0f%% %9.2f %9.2f\n", length_label(p.length).c_str(),
            1e3 * p.host_seconds, 1e3 * p.kernel_seconds, p.speedup(), p.gbytes_per_s(),
            p.copy_kernel_gbytes_per_s(), p.copy_buffer_gbytes_per_s(), percent_of_copy(p),
            p.six_vectors_gbytes_per_s(), p.one_record_gbytes_per_s());
  appendf(out, "  (6vec / rec: the paper's scatter alone, I' given, on its six vectors / on one 64-byte record)\n");
  if (!r.scatter_limit.empty()) appendf(out, "  (%s)\n", r.scatter_limit.c_str());
  if (!r.by_pes.empty()) {
    appendf(out, "  %s descriptors over PE counts (destination streams = PEs, one 64-byte record each):\n",
            length_label(r.by_pes.front().length).c_str());
    appendf(out, "  %8s %11s %8s %9s %9s %7s\n", "PEs", "kernel ms", "speedup", "GB/s", "copy GB/s", "%copy");
    for (const ScatterPoint& p : r.by_pes)
      appendf(out, "  %8d %11.4f %8.2f %9.2f %9.2f %6.0f%%\n", p.pes, 1e3 * p.kernel_seconds, p.speedup(),
              p.gbytes_per_s(), p.copy_kernel_gbytes_per_s(), percent_of_copy(p));
  }
  appendf(out, "  placement %s host_scatter at every length\n", r.all_verified() ? "matches" : "DIFFERS from");
}

}  // namespace

std::string bench_text(const BenchReport& r) {
  std::string out;
  header_text(out, r);
  renders_text(out, r);
  traversal_text(out, r);
  stages_text(out, r);
  prepare_text(out, r);
  phases_text(out, r);
  ranks_text(out, r);
  occupancy_text(out, r);
  memory_text(out, r);
  scatter_text(out, r);
  return out;
}

}  // namespace opsila
