// `opsila bench ... --compare OLD.json`: each figure of this run beside the
// same figure of a saved run, with the ratio this / saved.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace opsila {

// One comparable figure of a bench result.
struct BenchFigure {
  std::string name;  // "render seconds", "scatter 2^20 GB/s", ...
  double value = 0;
  bool higher_is_better = false;
};

// The figures a bench JSON holds (render, baselines, scatter curve, copy
// ceiling), in report order; figures a run lacks are left out.
// `saved`: the file of a saved run, whose figures are checked (InputError
// naming it and the figure); nullptr for this run's.
std::vector<BenchFigure> bench_figures(const nlohmann::json& results, const std::string* saved = nullptr);

// A saved bench JSON; throws InputError("--compare FILE: problem").
nlohmann::json read_saved_bench(const std::string& path);

// The comparison table: figures present in both runs, this run's value, the
// saved value and the ratio; notes when the runs' settings differ.
std::string compare_text(const nlohmann::json& now, const nlohmann::json& saved, const std::string& saved_path);

}  // namespace opsila
