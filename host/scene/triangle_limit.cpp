#include "scene/triangle_limit.h"

#include <algorithm>
#include <cstdio>

namespace opsila {

std::size_t triangles_for_memory(std::uint64_t bytes) {
  if (bytes <= kPrepareHostBaseBytes) return 0;
  return std::size_t(std::min<std::uint64_t>((bytes - kPrepareHostBaseBytes) / kPrepareHostBytesPerTriangle,
                                             kMaxTriangles));
}

std::uint64_t memory_for_triangles(std::size_t triangles) {
  return kPrepareHostBaseBytes + std::uint64_t(triangles) * kPrepareHostBytesPerTriangle;
}

HostMemory host_memory_of(std::uint64_t flag_bytes, std::uint64_t available, int local_ranks,
                          std::uint64_t address_space) {
  HostMemory m;
  m.local_ranks = std::max(local_ranks, 1);
  if (flag_bytes > 0) {
    m.bytes = flag_bytes, m.from_flag = true;
  } else {
    m.available = available;
    m.bytes = available / std::uint64_t(m.local_ranks);
    if (address_space > 0 && address_space < m.bytes) m.bytes = m.address_space = address_space;
  }
  return m;
}

TriangleLimit TriangleLimit::of_memory(const HostMemory& memory) {
  TriangleLimit limit;
  limit.memory = memory;
  limit.triangles = triangles_for_memory(memory.bytes);
  limit.why = limit.triangles < kMaxTriangles ? Why::memory : Why::ids;
  return limit;
}

TriangleLimit TriangleLimit::capped_for_tests(std::size_t n) const {
  if (n >= triangles) return *this;
  TriangleLimit limit = *this;
  limit.triangles = n;
  limit.why = Why::test_hook;
  return limit;
}

namespace {

std::string gib(std::uint64_t bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f GiB", double(bytes) / double(std::uint64_t(1) << 30));
  return text;
}

std::size_t per_rank(std::size_t triangles, int ranks) {
  const std::size_t r = std::size_t(std::max(ranks, 1));
  return triangles / r + (triangles % r != 0);
}

// "(--host-memory)", "(31.20 GiB available on this host, shared by 4 ranks)",
// "(the address space ulimit -v leaves this process)".
std::string memory_source(const HostMemory& m) {
  if (m.from_flag) return "(--host-memory)";
  if (m.address_space > 0) return "(the address space ulimit -v leaves this process)";
  return "(" + gib(m.available) + " available on this host" +
         (m.local_ranks > 1 ? ", shared by " + std::to_string(m.local_ranks) + " ranks" : std::string()) + ")";
}

}  // namespace

std::string TriangleLimit::why_not(std::size_t n, int ranks, bool more_than) const {
  switch (why) {
    case Why::given: return "";
    case Why::ids: return " (ids are 32-bit)";
    case Why::test_hook: return " (as lowered by OPSILA_RANK_TRIANGLE_LIMIT)";
    case Why::memory: break;
  }
  const bool several = ranks > 1;
  const std::uint64_t need = memory_for_triangles(per_rank(n, ranks));
  return std::string(": ") + (more_than ? "more than " : "") + std::to_string(n) + " triangles" +
         (several ? " on " + std::to_string(ranks) + " ranks" : std::string()) + " need " +
         (more_than ? "over " : "about ") + gib(need) + (several ? " a rank" : "") + " while preparing at " +
         std::to_string(kPrepareHostBytesPerTriangle) + " bytes a triangle, and " +
         (several ? "each rank" : "this process") + " may use " + gib(memory.bytes) + " " + memory_source(memory);
}

std::string TriangleLimit::objects_beyond(std::size_t n, std::size_t objects, std::uint64_t map_bytes) const {
  if (why != Why::memory) return "";
  const std::uint64_t need = memory_for_triangles(n) + std::uint64_t(objects) * kPrepareHostBytesPerObject + map_bytes;
  if (need <= memory.bytes) return "";
  const std::uint64_t mib = std::uint64_t(1) << 20;
  const std::string maps = map_bytes ? ", " + std::to_string((map_bytes + mib - 1) / mib) + " MiB of texture maps" : "";
  return ": " + std::to_string(objects) + " objects" + maps + " and " + std::to_string(n) + " triangles need about " +
         gib(need) +
         " while preparing at " + std::to_string(kPrepareHostBytesPerObject) + " bytes an object and " +
         std::to_string(kPrepareHostBytesPerTriangle) + " a triangle, and this process may use " + gib(memory.bytes) +
         " " + memory_source(memory) + "; " + (memory.address_space > 0 ? "a ulimit -v above " : "--host-memory ") +
         std::to_string((need + mib - 1) / mib) + "M would do";
}

std::string TriangleLimit::no_room() const {
  if (why != Why::memory || triangles > 0) return "";
  // Under ulimit -v the limit is what is left past the program and its
  // driver, plus the base: no triangle fits only when nothing is left, by
  // a deficit not known here.
  if (memory.address_space > 0)
    return "not enough address space to prepare a scene: ulimit -v leaves this process no room beyond the program "
           "and its OpenCL driver, and preparing takes " + std::to_string(kPrepareHostBaseBytes >> 20) +
           " MiB more before its first triangle; raise ulimit -v";
  return "not enough host memory to prepare a scene: this process may use " + gib(memory.bytes) + " " +
         memory_source(memory) + ", less than the " + gib(kPrepareHostBaseBytes) +
         " preparing takes before its first triangle; " + memory_hint(1, 1) + " would do for a small scene";
}

std::string TriangleLimit::memory_hint(std::size_t n, int ranks) const {
  const std::size_t share = per_rank(n, ranks);
  if (why != Why::memory || share > kMaxTriangles) return "";
  const std::uint64_t mib = std::uint64_t(1) << 20;
  const std::uint64_t need = (memory_for_triangles(share) + mib - 1) / mib;
  // Under ulimit -v the flag would promise what the process cannot map.
  if (memory.address_space > 0) return "a ulimit -v above " + std::to_string(need) + "M";
  return "--host-memory " + std::to_string(need) + "M";
}

}  // namespace opsila
