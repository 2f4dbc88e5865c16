// The bench's context block: date, host, CPUs, load and build type.
#include <unistd.h>

#include <cstdio>
#include <ctime>
#include <fstream>
#include <string>
#include <thread>

#include "bench/report.h"

namespace opsila {

namespace {

// "cpu MHz" and "model name" of the first processor in /proc/cpuinfo.
void read_cpuinfo(BenchContext& c) {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line) && (c.mhz_per_cpu == 0 || c.cpu_model.empty())) {
    const std::size_t colon = line.find(':');
    if (colon == std::string::npos || colon + 2 > line.size()) continue;
    const std::string key = line.substr(0, line.find_last_not_of(" \t", colon - 1) + 1);
    const std::string value = line.substr(colon + 2);
    if (key == "cpu MHz" && c.mhz_per_cpu == 0) c.mhz_per_cpu = std::atof(value.c_str());
    if (key == "model name" && c.cpu_model.empty()) c.cpu_model = value;
  }
}

}  // namespace

BenchContext gather_context() {
  BenchContext c;
  char when[32];
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  std::strftime(when, sizeof when, "%Y-%m-%dT%H:%M:%SZ", &utc);
  c.date = when;
  char host[256] = {0};
  if (::gethostname(host, sizeof host - 1) == 0) c.host_name = host;
  c.num_cpus = static_cast<int>(std::thread::hardware_concurrency());
  read_cpuinfo(c);
  std::ifstream load("/proc/loadavg");
  for (double& v : c.load_avg)
    if (!(load >> v)) v = -1;
#ifdef OPSILA_BUILD_TYPE
  c.build_type = OPSILA_BUILD_TYPE;
#endif
  if (c.build_type.empty()) c.build_type = "unknown";
  return c;
}

}  // namespace opsila
