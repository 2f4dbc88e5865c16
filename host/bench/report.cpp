// The bench report's derived figures: time by kernel, exchange and launch
// overhead shares, work and occupancy per level and PE, memory per bank.
#include "bench/report.h"

#include <algorithm>
#include <cmath>

#include "device/counters.h"
#include "formats/image/image_io.h"
#include "partition/pe_group.h"
#include "opsila_shared.h"

namespace opsila {

namespace {

bool is_scatter(const std::string& name) { return name.compare(0, 8, "scatter_") == 0; }

// Per level and PE: descriptors processed and intersection tests.
std::vector<LevelWork> level_work(const RenderStats& st) {
  std::vector<LevelWork> out;
  for (const auto& level : st.counters) {
    LevelWork w;
    for (const auto& c : level) {
      const std::uint64_t tests = c[OPSILA_STAT_TRI_TESTS] + c[OPSILA_STAT_BOX_TESTS];
      w.descriptors.push_back(c[OPSILA_STAT_TRACED]);
      w.tests.push_back(tests);
      w.tri_tests.push_back(c[OPSILA_STAT_TRI_TESTS]);
      w.box_tests.push_back(c[OPSILA_STAT_BOX_TESTS]);
      w.sphere_tests.push_back(c[OPSILA_STAT_SPHERE_TESTS]);
      w.total_descriptors += c[OPSILA_STAT_TRACED];
      w.total_tests += tests;
      w.max_descriptors = std::max<std::uint64_t>(w.max_descriptors, c[OPSILA_STAT_TRACED]);
      w.max_tests = std::max(w.max_tests, tests);
      w.spawned_radiance += c[OPSILA_STAT_SPAWN_RADIANCE];
      w.spawned_shadow += c[OPSILA_STAT_SPAWN_SHADOW];
      w.forwards += c[OPSILA_STAT_FORWARD];
      w.triangle_total += c[OPSILA_STAT_TRI_TESTS];
      w.box_total += c[OPSILA_STAT_BOX_TESTS];
      w.sphere_total += c[OPSILA_STAT_SPHERE_TESTS];
      w.route_total += c[OPSILA_STAT_ROUTE_TESTS];
    }
    out.push_back(std::move(w));
  }
  return out;
}

}  // namespace

Agreement compare_images(const std::vector<float>& a, const std::vector<float>& b) {
  Agreement g;
  if (a.size() != b.size() || a.empty()) return g;
  std::vector<float> ca(a), cb(b);
  for (auto* v : {&ca, &cb})
    for (float& x : *v) x = std::isnan(x) ? 0.0f : std::min(1.0f, std::max(0.0f, x));
  g.psnr = psnr(ca, cb, 1.0);
  std::size_t same = 0;
  for (std::size_t p = 0; p + 2 < a.size(); p += 3) {
    bool eq = true;
    for (int c = 0; c < 3; ++c) {
      g.max_abs_diff = std::max(g.max_abs_diff, double(std::fabs(a[p + c] - b[p + c])));
      eq = eq && a[p + c] == b[p + c];
    }
    same += eq;
  }
  g.identical_pixels = double(same) / double(a.size() / 3);
  return g;
}

std::optional<double> occupancy_of(std::uint64_t total, std::uint64_t max, std::size_t pes) {
  if (max == 0 || pes == 0) return std::nullopt;
  return double(total) / (double(pes) * double(max));
}

RankFigures rank_figures(const BenchReport& r) {
  RankFigures f;
  const std::vector<RankReport>& ranks = r.stats().ranks;
  f.traffic = rank_traffic(ranks);
  double exchange_max = 0;
  for (const RankReport& k : ranks) {
    f.frame_seconds = std::max(f.frame_seconds, k.render_seconds);
    exchange_max = std::max(exchange_max, k.exchange_seconds);
    if (k.render_seconds > 0) {
      f.exchange_share = std::max(f.exchange_share, k.exchange_seconds / k.render_seconds);
      f.exposed_share = std::max(f.exposed_share, k.exposed_seconds / k.render_seconds);
      f.mpi_share = std::max(f.mpi_share, k.mpi_seconds / k.render_seconds);
    }
  }
  const std::uint64_t rays = r.rays_total();
  f.seconds_per_descriptor = f.traffic.sent > 0 ? exchange_max / double(f.traffic.sent) : 0.0;
  f.seconds_per_ray = rays > 0 ? exchange_max / double(rays) : 0.0;
  f.descriptors_per_ray = rays > 0 ? double(f.traffic.sent) / double(rays) : 0.0;
  return f;
}

const char* launch_mode(const std::string& name) { return name == "spmd_phase" ? "SPMD" : "SIMD"; }

double mrays(std::uint64_t rays, double seconds) { return seconds > 0 ? double(rays) / seconds / 1e6 : 0.0; }

std::string length_label(std::size_t n) {
  if (n >= 1024 && (n & (n - 1)) == 0) {
    int k = 0;
    while ((std::size_t(1) << k) < n) ++k;
    return "2^" + std::to_string(k);
  }
  return std::to_string(n);
}

std::uint64_t BenchReport::rays_total() const {
  return opsila.rays.total();
}

std::vector<const BaselineRun*> BenchReport::baselines() const {
  std::vector<const BaselineRun*> out;
  for (const BaselineRun* b : {&megakernel, &sequential, &threads, &embree})
    if (b->present) out.push_back(b);
  return out;
}

std::optional<double> BenchReport::over_traversal(double seconds, std::uint64_t rays) const {
  if (!traversal.present || traversal.rays() == 0 || !(traversal.seconds > 0) || rays == 0) return std::nullopt;
  return (seconds / double(rays)) / (traversal.seconds / double(traversal.rays()));
}

std::optional<double> BenchReport::vs_embree(double mrays_per_s) const {
  if (!embree.present) return std::nullopt;
  const double e = mrays(embree.median_run.rays.total(), embree.seconds);
  if (!(e > 0)) return std::nullopt;
  return mrays_per_s / e;
}

double BenchReport::prepare_seconds() const {
  const PrepareTimes& t = stats().prepare;
  return t[PrepareStage::read] + t[PrepareStage::parse] + t[PrepareStage::partition] + t[PrepareStage::bank_build] +
         t[PrepareStage::upload];
}

bool BenchReport::all_verified() const {
  bool ok = true;
  for (const ScatterPoint& p : curve) ok = ok && p.verified;
  for (const ScatterPoint& p : by_pes) ok = ok && p.verified;
  return ok;
}

double BenchReport::replicated_over_bank_max() const {
  const std::uint64_t mine = bank_max + stats().global_bytes;
  return mine > 0 ? double(stats().replicated_bytes) / double(mine) : 0.0;
}

std::vector<StageTime> stage_times(const std::vector<std::uint64_t>& counters, double seconds, double clocked,
                                   StageClockCost* cost) {
  const std::size_t n = std::min<std::size_t>(counters.size(), OPSILA_STAGE_COUNT);
  const bool entries = counters.size() >= std::size_t(OPSILA_STAGE_COUNTERS);
  std::uint64_t all = 0, readings = 0;
  for (std::size_t s = 0; s < n; ++s) {
    all += counters[s];
    if (entries) readings += counters[OPSILA_STAGE_COUNT + s];
  }
  // The readings' cost: the cycles beyond what the timed frame's share of
  // them would be, evenly over the readings.
  const double over = clocked > seconds && seconds > 0 ? 1.0 - seconds / clocked : 0.0;
  const double per_entry = readings > 0 ? over * double(all) / double(readings) : 0.0;
  if (cost) *cost = {per_entry, readings > 0 ? over : 0.0};
  std::vector<StageTime> out;
  double kept = 0;
  for (std::size_t s = 0; s < n && all > 0; ++s) {
    if (counters[s] == 0) continue;
    StageTime t;
    t.name = stage_name(static_cast<int>(s));
    t.cycles = counters[s];
    t.entries = entries ? counters[OPSILA_STAGE_COUNT + s] : 0;
    t.raw_share = double(t.cycles) / double(all);
    t.share = std::max(0.0, double(t.cycles) - per_entry * double(t.entries));  // cycles, until divided below
    kept += t.share;
    out.push_back(t);
  }
  for (StageTime& t : out) {
    t.share = kept > 0 ? t.share / kept : t.raw_share;
    t.seconds = t.share * seconds;
  }
  return out;
}

void BenchReport::analyse() {
  const RenderStats& st = stats();
  by_kernel.clear();
  kernel_seconds = exchange_seconds = 0;
  launches_per_frame = 0;
  for (const LaunchRecord& l : st.launches) {
    KernelTime& e = by_kernel[l.name];
    e.launches += static_cast<int>(l.launches);
    launches_per_frame += static_cast<int>(l.launches);
    e.seconds += l.seconds;
    kernel_seconds += l.seconds;
    if (is_scatter(l.name)) exchange_seconds += l.seconds;
  }
  idle_seconds = host_late_seconds = 0;
  const LaunchRecord* prev = nullptr;
  for (const LaunchRecord& l : st.launches) {
    if (l.queued < 0) {
      prev = nullptr;
      continue;
    }
    if (prev) {
      const double end = prev->started + prev->seconds, gap = l.started - end;
      if (gap > 0) idle_seconds += gap, host_late_seconds += std::min(gap, std::max(0.0, l.queued - end));
    }
    prev = &l;
  }
  const double rs = st.render_seconds;
  overhead_seconds = std::max(0.0, rs - kernel_seconds);
  exchange_share = rs > 0 ? exchange_seconds / rs : 0;
  overhead_share = rs > 0 ? overhead_seconds / rs : 0;

  work = level_work(st);
  std::uint64_t all_tests = 0, all_max_tests = 0, all_max_desc = 0;
  all_descriptors = all_triangle_tests = all_box_tests = all_sphere_tests = all_route_tests = 0;
  for (const LevelWork& w : work) {
    all_tests += w.total_tests;
    all_max_tests += w.max_tests;
    all_descriptors += w.total_descriptors;
    all_max_desc += w.max_descriptors;
    all_triangle_tests += w.triangle_total;
    all_box_tests += w.box_total;
    all_sphere_tests += w.sphere_total;
    all_route_tests += w.route_total;
  }
  // The render's occupancy: work done over the work the phases would have
  // allowed if every PE had been as busy as the busiest one, level by level.
  occupancy = occupancy_of(all_tests, all_max_tests, std::size_t(pes));
  occupancy_descriptors = occupancy_of(all_descriptors, all_max_desc, std::size_t(pes));

  cross_rank_by_level.clear();
  if (ranks > 1) {
    const std::size_t P = std::size_t(st.num_pes);
    for (const auto& level : st.traffic) {
      std::uint64_t crossed = 0;
      for (std::size_t src = 0; src < P; ++src)
        for (std::size_t dst = 0; dst < P; ++dst)
          if (src * P + dst < level.size() &&
              rank_of_pe(int(P), ranks, int(src)) != rank_of_pe(int(P), ranks, int(dst)))
            crossed += level[src * P + dst];
      cross_rank_by_level.push_back(crossed);
    }
  }

  bank_max = bank_sum = 0;
  for (std::uint64_t b : st.bank_bytes) bank_max = std::max(bank_max, b), bank_sum += b;
  bank_mean = st.bank_bytes.empty() ? 0.0 : double(bank_sum) / double(st.bank_bytes.size());
}

}  // namespace opsila
