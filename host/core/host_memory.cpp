#include "core/host_memory.h"

#include <sys/resource.h>
#include <unistd.h>

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "core/errors.h"

namespace opsila {

std::uint64_t physical_memory() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  return pages > 0 && page > 0 ? std::uint64_t(pages) * std::uint64_t(page) : 0;
}

std::uint64_t address_space_left(std::uint64_t reserve) {
  struct rlimit rl {};
  if (::getrlimit(RLIMIT_AS, &rl) != 0 || rl.rlim_cur == RLIM_INFINITY) return 0;
  std::uint64_t pages = 0;
  std::ifstream statm("/proc/self/statm");  // its first field: the pages mapped now
  if (!(statm >> pages)) return 0;
  const std::uint64_t used = pages * std::uint64_t(sysconf(_SC_PAGESIZE));
  return rl.rlim_cur > used + reserve ? rl.rlim_cur - used - reserve : 1;
}

std::uint64_t available_host_memory() {
  std::ifstream in("/proc/meminfo");
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string key, unit;
    std::uint64_t kib = 0;
    if (words >> key >> kib >> unit && key == "MemAvailable:" && unit == "kB") return kib * 1024;
  }
  return physical_memory();  // an older kernel, or no /proc
}

std::optional<std::uint64_t> parse_memory_size(const std::string& text) {
  std::size_t i = 0;
  while (i < text.size() && (std::isdigit(static_cast<unsigned char>(text[i])) || text[i] == '.')) ++i;
  const std::string number = text.substr(0, i);
  if (number.empty() || number.find_first_of("0123456789") == std::string::npos ||
      number.find('.') != number.rfind('.'))
    return std::nullopt;
  std::string unit = text.substr(i);
  for (char& c : unit) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  int shift = 0;
  if (!unit.empty() && unit != "B") {
    const std::string units = "KMGT";
    const std::size_t u = units.find(unit[0]);
    const std::string rest = unit.substr(1);
    if (u == std::string::npos || !(rest.empty() || rest == "B" || rest == "IB")) return std::nullopt;
    shift = 10 * int(u + 1);
  }
  const double bytes = std::ldexp(std::strtod(number.c_str(), nullptr), shift);
  if (!(bytes >= 1) || bytes > std::ldexp(1.0, 60)) return std::nullopt;
  return static_cast<std::uint64_t>(bytes);
}

}  // namespace opsila
