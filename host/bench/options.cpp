#include "bench/options.h"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <thread>

#include "formats/image/image_io.h"

namespace opsila {

namespace {

CommandSyntax bench_syntax() {
  CommandSyntax syntax;
  syntax.command = "bench";
  syntax.flags = {{"--json", "--json", true},       {"--csv", "--csv", true},
                  {"--repeats", "--repeats", true}, {"--warmup", "--warmup", true},
                  {"--threads", "--threads", true}, {"--scatter-max", "--scatter-max", true},
                  {"--compare", "--compare", true}, {"--rays-out", "--rays-out", true},
                  {"--quick", "--quick", false},    {"-q", "-q", false},
                  {"--quiet", "-q", false},         {"-h", "--help", false},
                  {"--help", "--help", false}};
  syntax.flags.insert(syntax.flags.end(), view_flags().begin(), view_flags().end());
  // Render flags that make no sense for a benchmark.
  syntax.foreign = {"-o", "--output", "--item-buffer", "--stats", "--reference"};
  syntax.foreign_kind = "a render flag, not a bench flag";
  return syntax;
}

}  // namespace

int BenchOptions::host_threads() const {
  return threads.value_or(static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
}

int BenchOptions::host_repeats() const { return std::min(timed_repeats(), 3); }

BenchOptions parse_bench_options(const std::vector<std::string>& args) {
  BenchOptions o;
  walk_scene_command(args, bench_syntax(), o, [&](const std::string& flag, const std::string& name,
                                                  const std::string& value) {
    if (flag == "--json") {
      o.json_path = path_ending_in(name, value, ".json", "must end in .json");
    } else if (flag == "--compare") {
      o.compare_path = path_ending_in(name, value, ".json", "must end in .json (a saved --json result)");
    } else if (flag == "--rays-out") {
      o.rays_path = path_ending_in(name, value, ".rays", "must end in .rays");
    } else if (flag == "--csv") {
      if (value.empty()) bad_flag(name, value, "empty folder name");
      o.csv_dir = value;
    } else if (flag == "--repeats") {
      o.repeats = int_in_range(name, value, 1, 1000);
    } else if (flag == "--warmup") {
      o.warmup = int_in_range(name, value, 0, 100);
    } else if (flag == "--threads") {
      o.threads = int_in_range(name, value, 1, 1024);
    } else if (flag == "--scatter-max") {
      o.scatter_max_log2 = int_in_range(name, value, 4, 24);
    } else if (flag == "--quick") {
      o.quick = true;
    }
  });
  if (!o.help) check_view_flags(o);
  return o;
}

std::string bench_usage() {
  return "usage: opsila bench SCENE [view flags] [--json FILE] [--csv DIR] [--quick] [options]\n"
         "\n"
         "Measures, on one OpenCL device: the OPSILA render (phases, exchange share,\n"
         "launch overhead, PE occupancy, traffic, memory per bank), baselines on the\n"
         "same rays (replicated-scene megakernel on the same device, the sequential host\n"
         "reference on 1 and all threads, Embree when built in), and the scatter curve\n"
         "(speed-up and bandwidth against vector length, beside the copy bandwidth).\n"
         "Every figure is the median of repeated runs after a warm-up; compilation is\n"
         "never timed.\n"
         "\n"
         "  --json FILE        write every result as JSON (see docs/BENCHMARKS.md)\n"
         "  --csv DIR          write CSV tables: scatter, scatter_pes (not with --quick), phases,\n"
         "                     levels, occupancy, traffic, baselines; ranks, rank_traffic under mpirun\n"
         "  --compare OLD.json print each figure beside a saved --json result, with the ratio\n"
         "  --rays-out F.rays  write the traversal alone's triangles, rays and answers, for\n"
         "                     timing other kernels on the same rays (see docs/BENCHMARKS.md)\n"
         "  --quick            fewer repeats and shorter scatter vectors (CI)\n"
         "  --repeats N        timed runs per measurement (default 5, --quick 2)\n"
         "  --warmup N         untimed runs before them (default 1)\n"
         "  --threads N        host threads for the host baselines (default: all)\n"
         "  --scatter-max K    longest scatter vector 2^K, 4..24 (default 24, --quick 16)\n"
         "  -q, --quiet        no progress lines\n"
         "  -h, --help         this text\n"
         "\n"
         "View flags, as for 'opsila render': --size WxH, --eye, --look-at, --up, --fov,\n"
         "--light, --ambient, --background, --depth, --spp, --pes, --device, --bank-capacity, --smooth,\n"
         "--routing boxes|spheres, --work-groups-per-pe, --balance facets|work|measured,\n"
         "--host-memory SIZE.\n"
         "The bench's --balance is measured unless given (render's is facets): five small\n"
         "pilot frames measure each cluster's work first, outside the timed runs; a scene\n"
         "with instances, which pilot frames do not measure, is balanced by work.\n"
         "\n"
         "Under mpirun every rank drives its device and its group of PEs, and reads only\n"
         "its share of a JSON scene, with any --balance. The report gives every rank's\n"
         "figures (facets read and held, peak host\n"
         "memory, reading, partition, exchange, bank-build and frame times); the\n"
         "baselines and the scatter curve, which need one process, are left out.\n";
}

}  // namespace opsila
