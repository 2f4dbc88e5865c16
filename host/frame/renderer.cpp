// The OPSILA host loop, as the paper runs a frame: item buffer (SIMD),
// primary descriptors, then rounds of exchange (SIMD scatter) + SPMD phase
// until no descriptor is left, then the image. Each stage lives in a file
// of its own (frame/frame.h lists them).
#include "frame/renderer.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>

#include "core/progress.h"
#include "device/counters.h"
#include "frame/frame.h"
#include "frame/stats.h"

namespace opsila {

const char* balance_name(Balance b) {
  switch (b) {
    case Balance::work: return "work";
    case Balance::measured: return "measured";
    default: return "facets";
  }
}

Renderer::Renderer(const Scene& scene, PreparedBanks banks, const RenderSettings& settings, ClRuntime& runtime)
    : m_(std::make_unique<Machine>(scene, std::move(banks), settings, runtime)) {}

Renderer::~Renderer() = default;

Renderer::Machine::~Machine() {
  rt.queue().finish();  // its error, if any, was the frame's: nothing more to say here
}

// One frame, as the paper runs it.
void Renderer::count_work(bool on) {
  Machine& m = *m_;
  if (m.measure || !(on ? m.work_kernels : m.ray_kernels).built)
    throw std::logic_error("Renderer::count_work: the machine was not prepared to switch (switch_counting)");
  m.counting = on;
  m.traffic_levels = on ? m.counted_traffic_levels : 0;
}

void Renderer::count_stage_cycles(bool on) {
  Machine& m = *m_;
  if (m.measure || !m.stage_kernels.built)
    throw std::logic_error("Renderer::count_stage_cycles: the machine was not prepared for it (stage_cycles)");
  m.clocking = on;
  m.traffic_levels = on || !m.counting ? 0 : m.counted_traffic_levels;  // the clocks count no work
}

std::vector<std::uint64_t> Renderer::stage_cycles() {
  Machine& m = *m_;
  if (!m.clocking) return {};
  return read_counters(m.rt, m.work.cost, OPSILA_STAGE_COUNTERS, "SPMD phase stage cycles");
}

RenderResult Renderer::render() {
  RenderResult result;
  render(result);
  return result;
}

void Renderer::render(RenderResult& result) {
  Machine& m = *m_;
  result.rays = RayCounts();
  result.width = m.width;
  result.height = m.height;
  result.stats = m.prepared;
  RenderStats& st = result.stats;
  Launcher launch(m.rt, st.launches);
  launch.set_sparse(m.sparse_launches);
  // Several ranks: from here on they wait on each other (a rank that failed
  // while preparing has said so, and every rank stops here).
  const bool ranks = !m.group.all();
  if (ranks) m.ranks.begin_collective();
  const auto t_start = std::chrono::steady_clock::now();
  const double mpi_start = m.ranks.mpi_seconds();

  if (m.progress) m.progress->start();
  m.clear_frame();
  // Even k: the centre ray is no sample; its pass writes the item buffer alone.
  if (m.spp_k % 2 == 0 && m.item_output) m.item_buffer(launch, -1);
  m.item_buffer(launch, 0);
  Machine::Frame f;
  f.listed = m.list_hits(launch, 0);
  for (int round = 0;; ++round) {
    if (round == m.fault_round)
      throw ClError("device fault at round " + std::to_string(round) + " (injected by OPSILA_FAULT_ROUND)");
    m.primary_descriptors(launch, f, round);
    if (!ranks && f.pool_len == 0 && f.out_groups == 0) break;
    m.exchange(launch, f, round, st);
    if (f.groups == 0) {  // only NIL holes were left: nothing placed, nothing waits
      f.out_groups = 0;
      if (ranks && !m.end_rank_round(launch, f)) break;
      continue;
    }
    m.spmd_phase(launch, f, round);
    ++st.rounds;
    if (ranks && !m.end_rank_round(launch, f)) break;
    if (m.progress && m.progress->due()) m.report_progress(f);
  }
  const auto t_read = std::chrono::steady_clock::now();
  m.read_image(launch, result);
  const auto t_end = std::chrono::steady_clock::now();
  st.readback_seconds = std::chrono::duration<double>(t_end - t_read).count();
  st.render_seconds = std::chrono::duration<double>(t_end - t_start).count();
  launch.harvest();
  if (m.first_frame) {
    // Compiling is not rendering: a driver that compiles at the first launch
    // (PoCL) would otherwise make the first frame look slow.
    const double waits = std::min(compile_waits(st.launches), st.render_seconds);
    st.render_seconds -= waits;
    st.kernel_compile_seconds = m.rt.build_seconds() + waits;
    m.first_frame = false;
  }
  if (ranks) {
    const RankReport mine = m.rank_report(st, st.render_seconds, m.ranks.mpi_seconds() - mpi_start);
    for (const std::string& text : m.ranks.gather(rank_report_json(mine), 0))
      st.ranks.push_back(rank_report_from_json(text));
  }
  m.read_stats(result);
  if (ranks) m.ranks.end_collective();
  if (m.progress && m.progress->due()) m.progress->report(1.0, result.rays.total());
}

std::vector<std::uint64_t> Renderer::cluster_work() {
  Machine& m = *m_;
  if (!m.measure) return {};
  std::vector<cl_uint> raw(m.ncost);
  cl_check(m.rt.queue().enqueueReadBuffer(m.work.cost, CL_TRUE, 0, raw.size() * sizeof(cl_uint), raw.data()),
           "clEnqueueReadBuffer(cluster work)");
  // A cluster is counted by the rank that holds it alone (the others count
  // 0 for it), so the largest count over the ranks is its count.
  std::vector<std::uint64_t> cost(raw.begin(), raw.end());
  if (!m.group.all()) m.ranks.max(cost);
  return cost;
}

std::uint64_t Renderer::planned_device_bytes() const { return m_->plan.total(); }

std::map<std::string, std::uint64_t> Renderer::planned_buffers() const {
  std::map<std::string, std::uint64_t> by_name;
  for (const BufferSpec& s : m_->buffers) by_name[s.name] += s.bytes();
  return by_name;
}

std::uint64_t Renderer::in_place_bytes() const { return m_->in_place_bytes; }

}  // namespace opsila
