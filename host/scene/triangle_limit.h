// How many triangles one process may take: what its host memory holds while
// it prepares them (scenes/FORMAT.md "Limits"), under the ceiling that the
// 32-bit ids set. Every reader is handed this limit by its caller; the
// messages that refuse a scene over it are written here.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace opsila {

// Ids ceiling: facet ids, object ids and bank indices are 32-bit signed, so
// no scene, share or entry may have more triangles, whatever the memory.
constexpr std::size_t kMaxTriangles = (std::size_t(1) << 31) - 1;

// Host memory that preparing a scene holds at its peak (reading, the
// partition, the bank build): a fixed base for the program and its buffers,
// and this much per triangle of the rank's share. The one figure every
// limit and message reads; above the measured peaks at the default 16 PEs
// (one process 87-94 bytes, a rank of 4 97-110: docs/DISTRIBUTED.md, "Cost
// model"), so that a scene accepted fits.
constexpr std::uint64_t kPrepareHostBaseBytes = std::uint64_t(256) << 20;
constexpr std::uint64_t kPrepareHostBytesPerTriangle = 120;
// And this much per object beyond its triangles: each small object is a
// cluster of its own, with its boxes and its bank BVH's root (3 M objects of
// one triangle each peaked 673 bytes an object above one object of 3 M).
constexpr std::uint64_t kPrepareHostBytesPerObject = 768;

// Triangles that `bytes` of host memory prepare (0 below the base), at most
// kMaxTriangles; and the bytes that preparing `triangles` takes.
std::size_t triangles_for_memory(std::uint64_t bytes);
std::uint64_t memory_for_triangles(std::size_t triangles);

// The host memory one process may use, and where the figure came from.
struct HostMemory {
  std::uint64_t bytes = 0;
  bool from_flag = false;        // --host-memory; else `available` shared by the local ranks
  std::uint64_t available = 0;   // the memory available on the host (without the flag)
  int local_ranks = 1;           // the ranks that run on that host
  std::uint64_t address_space = 0;  // the address space ulimit -v leaves, when it is the smaller; else 0
};
// `flag_bytes` (--host-memory) when nonzero, else `available` divided
// among the `local_ranks` on this host, or `address_space` (what ulimit -v
// leaves this process; 0: no limit) where that is less.
HostMemory host_memory_of(std::uint64_t flag_bytes, std::uint64_t available, int local_ranks,
                          std::uint64_t address_space = 0);

// One rank's triangle limit and why it is what it is.
struct TriangleLimit {
  enum class Why { ids, given, memory, test_hook };
  std::size_t triangles = kMaxTriangles;
  Why why = Why::ids;
  HostMemory memory;  // with Why::memory

  TriangleLimit() = default;
  // A bare number (a library caller's or a test's), so implicit: no memory
  // story in its messages.
  TriangleLimit(std::size_t n)
      : triangles(n < kMaxTriangles ? n : kMaxTriangles), why(n < kMaxTriangles ? Why::given : Why::ids) {}
  static TriangleLimit of_memory(const HostMemory& memory);
  // The limit lowered to `n` by OPSILA_RANK_TRIANGLE_LIMIT when it is lower.
  TriangleLimit capped_for_tests(std::size_t n) const;

  // Why `triangles` (on `ranks` ranks; `more_than`: at least that many, a
  // stream's count) do not fit: ": 1000000 triangles need about 0.37 GiB
  // while preparing at 120 bytes a triangle, and this process may use 0.29
  // GiB (--host-memory)"; "" for a given number.
  std::string why_not(std::size_t triangles, int ranks, bool more_than = false) const;
  // Why one process's `triangles` in `objects` objects, with `map_bytes`
  // of decoded texture maps, do not fit, counting kPrepareHostBytesPerObject
  // and the maps as well (": 3000000 objects and ... need
  // about 2.4 GiB ..., and this process may use 0.68 GiB (--host-memory);
  // --host-memory 2476M would do"); "" when they fit or memory is not what
  // limits.
  std::string objects_beyond(std::size_t triangles, std::size_t objects, std::uint64_t map_bytes = 0) const;
  // Why no triangle at all fits (the memory is below what preparing takes
  // before the first): "this process may use 0.10 GiB (--host-memory),
  // less than the 0.25 GiB ...; --host-memory 257M would do"; "" otherwise.
  std::string no_room() const;
  // "--host-memory 371M" when that much memory a rank would take
  // `triangles` on `ranks` ranks; "" when memory is not what limits.
  std::string memory_hint(std::size_t triangles, int ranks) const;
};

}  // namespace opsila
