// `opsila bench` arguments: the view group shared with `opsila render`
// (app/args.h) and the bench's own flags, with the defaults they imply.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "app/args.h"

namespace opsila {

struct BenchOptions : ViewOptions {
  std::string json_path, csv_dir;
  std::string compare_path;  // --compare: a saved --json result
  std::string rays_path;     // --rays-out: the traversal alone's rays and answers (bench/ray_file.h)
  bool quick = false, quiet = false, help = false;
  std::optional<int> repeats, warmup, threads, scatter_max_log2;

  // The settings the flags imply (defaults depend on --quick).
  int timed_repeats() const { return repeats.value_or(quick ? 2 : 5); }
  int warmup_runs() const { return warmup.value_or(1); }
  int host_threads() const;
  int host_repeats() const;  // the host baselines are slow: at most 3
  int scatter_max() const { return scatter_max_log2.value_or(quick ? 16 : 24); }
};

// Parses the arguments after "bench". Throws InputError naming the flag.
BenchOptions parse_bench_options(const std::vector<std::string>& args);
std::string bench_usage();


}  // namespace opsila
