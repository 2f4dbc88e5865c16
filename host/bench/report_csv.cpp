// The bench's --csv tables: scatter, scatter_pes, phases, levels, occupancy,
// traffic, baselines (one file each).
#include <cstdio>
#include <sstream>

#include "bench/report.h"
#include "formats/image/image_io.h"
#include "formats/image/output_files.h"

namespace opsila {

namespace {

std::string num(double v) {
  char s[64];
  std::snprintf(s, sizeof s, "%.9g", v);
  return s;
}

std::string optional_num(const std::optional<double>& v) { return v ? num(*v) : ""; }

double fraction_of_copy(const ScatterPoint& p) {
  return p.copy_kernel_gbytes_per_s() > 0 ? p.gbytes_per_s() / p.copy_kernel_gbytes_per_s() : 0;
}

std::string scatter_csv(const std::vector<ScatterPoint>& curve) {
  std::ostringstream c;
  c << "length,moved,bytes,host_seconds,kernel_seconds,speedup,gbytes_per_s,copy_kernel_gbytes_per_s,"
       "copy_buffer_gbytes_per_s,fraction_of_copy,count_seconds,plan_seconds,move_seconds\n";
  for (const ScatterPoint& p : curve)
    c << p.length << ',' << p.moved << ',' << num(p.bytes()) << ',' << num(p.host_seconds) << ','
      << num(p.kernel_seconds) << ',' << num(p.speedup()) << ',' << num(p.gbytes_per_s()) << ','
      << num(p.copy_kernel_gbytes_per_s()) << ',' << num(p.copy_buffer_gbytes_per_s()) << ','
      << num(fraction_of_copy(p)) << ',' << num(p.count_seconds) << ','
      << num(p.plan_seconds) << ',' << num(p.move_seconds) << '\n';
  return c.str();
}

std::string scatter_pes_csv(const std::vector<ScatterPoint>& by_pes) {
  std::ostringstream cp;
  cp << "pes,length,kernel_seconds,host_seconds,speedup,gbytes_per_s,copy_kernel_gbytes_per_s,fraction_of_copy\n";
  for (const ScatterPoint& p : by_pes)
    cp << p.pes << ',' << p.length << ',' << num(p.kernel_seconds) << ',' << num(p.host_seconds) << ','
       << num(p.speedup()) << ',' << num(p.gbytes_per_s()) << ',' << num(p.copy_kernel_gbytes_per_s()) << ','
       << num(fraction_of_copy(p)) << '\n';
  return cp.str();
}

std::string phases_csv(const RenderStats& st) {
  std::ostringstream ph;
  ph << "index,name,mode,round,seconds\n";
  for (std::size_t i = 0; i < st.launches.size(); ++i)
    ph << i << ',' << st.launches[i].name << ',' << launch_mode(st.launches[i].name) << ',' << st.launches[i].round
       << ',' << num(st.launches[i].seconds) << '\n';
  return ph.str();
}

std::string levels_csv(const BenchReport& r) {
  std::ostringstream lv;
  lv << "level,descriptors,tests,max_pe_descriptors,max_pe_tests,occupancy_descriptors,occupancy\n";
  for (std::size_t l = 0; l < r.work.size(); ++l) {
    const LevelWork& w = r.work[l];
    lv << l << ',' << w.total_descriptors << ',' << w.total_tests << ',' << w.max_descriptors << ',' << w.max_tests
       << ',' << optional_num(occupancy_of(w.total_descriptors, w.max_descriptors, std::size_t(r.pes))) << ','
       << optional_num(occupancy_of(w.total_tests, w.max_tests, std::size_t(r.pes))) << '\n';
  }
  return lv.str();
}

std::string occupancy_csv(const BenchReport& r) {
  std::ostringstream oc;
  oc << "level,pe,descriptors,triangle_tests,box_tests,sphere_tests,tests\n";
  for (std::size_t l = 0; l < r.work.size(); ++l)
    for (int p = 0; p < r.pes; ++p)
      oc << l << ',' << p << ',' << r.work[l].descriptors[p] << ',' << r.work[l].tri_tests[p] << ','
         << r.work[l].box_tests[p] << ',' << r.work[l].sphere_tests[p] << ',' << r.work[l].tests[p] << '\n';
  return oc.str();
}

std::string traffic_csv(const RenderStats& st, int P) {
  std::ostringstream tr;
  tr << "level,src,dst,descriptors\n";
  for (std::size_t l = 0; l < st.traffic.size(); ++l)
    for (int s = 0; s < P; ++s)
      for (int d = 0; d < P; ++d) {
        const std::uint64_t v = st.traffic[l][std::size_t(s) * P + d];
        if (v) tr << l << ',' << s << ',' << d << ',' << v << '\n';
      }
  return tr.str();
}

std::string baselines_csv(const BenchReport& r) {
  std::ostringstream bl;
  bl << "name,seconds,rays,mrays_per_s\n";
  bl << "opsila," << num(r.render_seconds) << ',' << r.rays_total() << ','
     << num(mrays(r.rays_total(), r.render_seconds)) << '\n';
  for (const BaselineRun* b : r.baselines())
    bl << b->name << ',' << num(b->seconds) << ',' << b->median_run.rays.total() << ','
       << num(mrays(b->median_run.rays.total(), b->seconds)) << '\n';
  if (r.traversal.present)
    bl << "traversal_alone," << num(r.traversal.seconds) << ',' << r.traversal.rays() << ','
       << num(mrays(r.traversal.rays(), r.traversal.seconds)) << '\n';
  return bl.str();
}

// Several MPI ranks: one row per rank, and the descriptors between ranks.
std::string ranks_csv(const BenchReport& r) {
  const RankTraffic t = rank_traffic(r.stats().ranks);
  std::ostringstream out;
  out << "rank,pe_begin,pe_end,device_bytes,scene_bytes,host_peak_bytes,render_seconds,exchange_seconds,"
         "exposed_seconds,mpi_seconds,sent,received,facets_read,facets_held,texture_bytes,read_seconds,partition_seconds,"
         "share_exchange_seconds,bank_seconds,pilot_facets_held\n";
  for (const RankReport& k : r.stats().ranks) {
    out << k.rank << ',' << k.pe_begin << ',' << k.pe_end << ',' << k.device_bytes << ',' << k.scene_bytes << ','
        << k.host_peak_bytes << ',' << num(k.render_seconds) << ',' << num(k.exchange_seconds) << ','
        << num(k.exposed_seconds) << ',' << num(k.mpi_seconds) << ',' << t.sent_by_rank[std::size_t(k.rank)] << ','
        << t.received_by_rank[std::size_t(k.rank)];
    // A scene read in shares: what the rank read and held, and its preparation; empty otherwise.
    const ShareFigures& s = k.share;
    if (s.active)
      out << ',' << s.facets_read << ',' << s.facets_held << ',' << s.texture_bytes << ',' << num(s.read_seconds) << ','
          << num(s.partition_seconds) << ',' << num(s.exchange_seconds) << ',' << num(s.bank_seconds) << ','
          << s.pilot_facets_held << '\n';
    else
      out << ",,,,,,,,\n";
  }
  return out.str();
}

std::string rank_traffic_csv(const BenchReport& r) {
  const RankTraffic t = rank_traffic(r.stats().ranks);
  std::ostringstream out;
  out << "round,from,to,descriptors\n";
  for (std::size_t k = 0; k < t.rounds.size(); ++k)
    for (std::size_t src = 0; src < t.rounds[k].size(); ++src)
      for (std::size_t dst = 0; dst < t.rounds[k][src].size(); ++dst)
        if (const std::uint64_t n = t.rounds[k][src][dst]) out << k << ',' << src << ',' << dst << ',' << n << '\n';
  return out.str();
}

}  // namespace

std::vector<std::string> bench_csv_tables(bool quick, int ranks) {
  std::vector<std::string> names;
  if (ranks == 1) names.push_back("scatter.csv");
  if (ranks == 1 && !quick) names.push_back("scatter_pes.csv");
  for (const char* n : {"phases.csv", "levels.csv", "occupancy.csv", "traffic.csv", "baselines.csv"}) names.push_back(n);
  if (ranks > 1) names.insert(names.end(), {"ranks.csv", "rank_traffic.csv"});
  return names;
}

void write_bench_csv(const BenchReport& r, const std::string& dir, OutputFiles& outputs) {
  const auto write = [&](const char* name, const std::string& text) { outputs.write(dir + "/" + name, text); };
  if (!r.curve.empty()) write("scatter.csv", scatter_csv(r.curve));
  if (!r.by_pes.empty()) write("scatter_pes.csv", scatter_pes_csv(r.by_pes));
  write("phases.csv", phases_csv(r.stats()));
  write("levels.csv", levels_csv(r));
  write("occupancy.csv", occupancy_csv(r));
  write("traffic.csv", traffic_csv(r.stats(), r.pes));
  write("baselines.csv", baselines_csv(r));
  if (r.ranks > 1) {
    write("ranks.csv", ranks_csv(r));
    write("rank_traffic.csv", rank_traffic_csv(r));
  }
}

}  // namespace opsila
