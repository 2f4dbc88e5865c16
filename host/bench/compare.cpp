#include "bench/compare.h"

#include <climits>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "bench/report.h"
#include "core/input_file.h"
#include "core/util.h"
#include "formats/common/json_text.h"
#include "scene/scene.h"

namespace opsila {

namespace {

using nlohmann::json;

// The figures of a run; `saved` names the file of a saved one, whose
// figures are checked: each a finite number >= 0 where present (an edited
// -1 had printed a negative ratio, a string had dropped its row unsaid).
struct Figures {
  std::vector<BenchFigure> out;
  const std::string* saved = nullptr;

  void add(const std::string& name, const json& j, const char* key, bool higher) {
    if (!j.is_object() || !j.contains(key)) return;
    const json& v = j[key];
    const bool sound = v.is_number() && std::isfinite(v.get<double>()) && v.get<double>() >= 0;
    if (sound) out.push_back({name, v.get<double>(), higher});
    else if (saved)
      throw InputError("--compare " + *saved + ": " + name + " ('" + key + "'): expected a number >= 0, not " +
                       quoted_prefix(v.dump()));
  }
};

std::string number(double v) {
  char s[32];
  std::snprintf(s, sizeof s, "%.4g", v);
  return s;
}

// "scene, WxH, depth D, P PEs" of a run, for the settings note.
std::string settings_of(const json& j) {
  std::ostringstream s;
  const json none;
  const json& scene = j.value("scene", none);
  const json& image = j.value("image", none);
  s << (scene.is_object() ? scene.value("path", std::string("?")) : std::string("?")) << ", "
    << (image.is_object() ? image.value("width", 0) : 0) << "x" << (image.is_object() ? image.value("height", 0) : 0)
    << ", depth " << j.value("depth", 0) << ", " << j.value("pes", 0) << " PEs";
  return s.str();
}

}  // namespace

std::vector<BenchFigure> bench_figures(const json& j, const std::string* saved) {
  Figures f{{}, saved};
  f.add("compile seconds", j, "compile_seconds", false);
  if (j.contains("render")) {
    const json& r = j["render"];
    f.add("render seconds", r, "seconds", false);
    f.add("render Mrays/s", r, "mrays_per_s", true);
    f.add("render kernel seconds", r, "kernel_seconds", false);
    f.add("render exchange share", r, "exchange_share", false);
    f.add("render launch overhead share", r, "overhead_share", false);
    f.add("render occupancy", r, "occupancy", true);
  }
  if (j.contains("baselines") && j["baselines"].is_object())
    for (const auto& [name, b] : j["baselines"].items()) {
      f.add(name + " seconds", b, "seconds", false);
      f.add(name + " Mrays/s", b, "mrays_per_s", true);
    }
  if (j.contains("scatter") && j["scatter"].is_array())
    for (const json& p : j["scatter"]) {
      if (!p.contains("length") || !p["length"].is_number_integer() || p["length"].get<std::int64_t>() < 0) continue;
      const std::string at = "scatter " + length_label(p["length"].get<std::uint64_t>());
      f.add(at + " kernel seconds", p, "kernel_seconds", false);
      f.add(at + " GB/s", p, "gbytes_per_s", true);
      f.add(at + " speed-up", p, "speedup", true);
      f.add(at + " copy GB/s", p, "copy_kernel_gbytes_per_s", true);
      f.add(at + " six-vector scatter GB/s", p, "six_vectors_gbytes_per_s", true);
      f.add(at + " one-record scatter GB/s", p, "one_record_gbytes_per_s", true);
    }
  f.add("copy ceiling GB/s", j, "copy_gbytes_per_s", true);
  return f.out;
}

namespace {

// The settings compare_text reads from a saved run, each where it is
// present of the type it must have, so that a hand-edited file is refused
// when it is read (before any work or output), naming the key.
void check_saved_settings(const json& j, const std::string& path) {
  const auto need = [&](const json& parent, const std::string& where, const char* key, bool text) {
    if (!parent.contains(key)) return;
    const json& v = parent[key];
    if (text ? v.is_string() : v.is_number_unsigned() && v.get<std::uint64_t>() <= std::uint64_t(INT_MAX)) return;
    throw InputError("--compare " + path + ": " + where + key + ": expected " +
                     (text ? "a string" : "a whole number from 0 to " + std::to_string(INT_MAX)));
  };
  const auto object = [&](const char* key) {
    if (j.contains(key) && !j[key].is_object())
      throw InputError("--compare " + path + ": " + key + ": expected an object");
    return j.contains(key);
  };
  need(j, "", "device", true);
  need(j, "", "depth", false);
  need(j, "", "pes", false);
  if (object("context")) {
    need(j["context"], "context.", "date", true);
    need(j["context"], "context.", "host_name", true);
  }
  if (object("scene")) need(j["scene"], "scene.", "path", true);
  if (object("image")) {
    need(j["image"], "image.", "width", false);
    need(j["image"], "image.", "height", false);
  }
}

}  // namespace

json read_saved_bench(const std::string& path) {
  // A saved bench result is a few hundred KiB, a few levels deep: its shape
  // is checked before the parse, which took 3 GB for 40 MiB of '['.
  const std::string text = read_named_file("--compare ", path, std::size_t(16) << 20);
  check_json_shape(text, "--compare " + path, 16, 4096);
  json j = json::parse(text, nullptr, false);
  if (j.is_discarded()) throw InputError("--compare " + path + ": not JSON");
  // A key given twice (an edited file): the parse keeps the last, so a
  // figure compared could be either; opsila writes each once.
  std::vector<std::string> repeated;
  (void)JsonLines(text, "--compare " + path, repeated);
  if (!repeated.empty()) {
    std::string first = repeated.front();
    first.resize(first.rfind("; the last one is used"));
    throw InputError(first + " (a saved bench result holds each key once)");
  }
  if (!j.is_object() || !j.contains("render") || !j["render"].is_object())
    throw InputError("--compare " + path + ": not an opsila bench result (no \"render\" block)");
  check_saved_settings(j, path);
  (void)bench_figures(j, &path);
  return j;
}

std::string compare_text(const json& now, const json& saved, const std::string& saved_path) {
  // The saved file's strings are shown as a terminal line shows them (a NUL
  // or an escape sequence in a saved string is no part of the report).
  std::string out = "\ncompared with " + shown_text(saved_path);
  if (saved.contains("context") && saved["context"].is_object())
    out += " (" + shown_text(saved["context"].value("date", std::string("undated"))) + ", " +
           shown_text(saved["context"].value("host_name", std::string("?"))) + ")";
  out += ":\n";
  if (settings_of(now) != settings_of(saved))
    out += "  note: the runs differ: this one " + settings_of(now) + "; saved " + shown_text(settings_of(saved)) + "\n";
  if (now.value("device", std::string()) != saved.value("device", std::string()))
    out += "  note: the saved run was on " + shown_text(saved.value("device", std::string("another device"))) + "\n";
  char line[256];
  std::snprintf(line, sizeof line, "  %-40s %12s %12s %8s\n", "figure", "this run", "saved", "ratio");
  out += line;
  const std::vector<BenchFigure> old_figures = bench_figures(saved);
  for (const BenchFigure& f : bench_figures(now)) {
    for (const BenchFigure& g : old_figures) {
      if (g.name != f.name) continue;
      const std::string ratio = g.value != 0 ? number(f.value / g.value) + "x" : "-";
      std::snprintf(line, sizeof line, "  %-40s %12s %12s %8s%s\n", f.name.c_str(), number(f.value).c_str(),
                    number(g.value).c_str(), ratio.c_str(), f.higher_is_better ? "" : " (lower is better)");
      out += line;
      break;
    }
  }
  return out;
}

}  // namespace opsila
