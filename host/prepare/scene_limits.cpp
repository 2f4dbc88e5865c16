#include "prepare/scene_limits.h"

#include <cmath>
#include <vector>

#include "core/host_memory.h"
#include "core/util.h"
#include "device/memory_plan.h"

namespace opsila {

namespace {

// One rank's figures as they travel between ranks.
struct MemoryRecord {
  std::uint64_t bytes, available, address_space;
  std::int32_t from_flag, local_ranks;
};

// What a process's address space must keep beyond the scene: the OpenCL
// driver's compiler and buffers (a CPU device's plan has its own check).
constexpr std::uint64_t kAddressSpaceReserve = std::uint64_t(256) << 20;

}  // namespace

HostMemory agree_host_memory(Ranks& ranks, const HostMemory& mine) {
  const std::vector<MemoryRecord> all = records_of<MemoryRecord>(ranks.all_gather(bytes_of(std::vector<MemoryRecord>{
      {mine.bytes, mine.available, mine.address_space, mine.from_flag ? 1 : 0, mine.local_ranks}})));
  const MemoryRecord* least = &all.front();
  for (const MemoryRecord& r : all)
    if (r.bytes < least->bytes) least = &r;  // the first of equals: every rank picks the same
  HostMemory m;
  m.bytes = least->bytes, m.available = least->available, m.address_space = least->address_space;
  m.from_flag = least->from_flag != 0, m.local_ranks = least->local_ranks;
  return m;
}

TriangleLimit host_triangle_limit(Ranks& ranks, std::uint64_t flag_bytes) {
  const std::uint64_t available = flag_bytes ? 0 : available_host_memory();
  // What is mapped now (the program, the driver) is already taken off, so
  // the limit's fixed base for the program is given back.
  const std::uint64_t left = flag_bytes ? 0 : address_space_left(kAddressSpaceReserve);
  const std::uint64_t address_space = left ? left + kPrepareHostBaseBytes : 0;
  const HostMemory mine = host_memory_of(flag_bytes, available, ranks.local_size(), address_space);
  // A rank that failed before (its device, its flags) waits in the failure
  // agreement: meet it there first, not in a collective it never joins.
  ranks.checkpoint();
  return TriangleLimit::of_memory(agree_host_memory(ranks, mine));
}

void check_device_room(const Scene& scene, const std::string& path, Ranks& ranks, const ClRuntime& runtime) {
  const std::uint64_t all = scene.total_triangles(), n = std::uint64_t(std::max(ranks.size(), 1));
  const std::uint64_t share = (all + n - 1) / n;
  const std::uint64_t need = share * kDeviceBytesPerTriangle, room = runtime.global_mem();
  if (need <= room) return;
  const std::uint64_t enough = (all * kDeviceBytesPerTriangle + room - 1) / std::max<std::uint64_t>(room, 1);
  const std::string hint = ranks.built_with_mpi() && enough <= 1024
                               ? ": it needs at least " + std::to_string(enough) + " MPI ranks, each with such a device (mpirun -n " +
                                     std::to_string(enough) + " opsila render ...)"
                               : "";
  throw ClError(path + ": " + std::to_string(share) + " triangles" +
                (n > 1 ? " (this rank's share of " + std::to_string(all) + ")" : std::string()) + " need about " +
                format_size(need) + " of device memory at " + std::to_string(kDeviceBytesPerTriangle) +
                " bytes a triangle, more than the device's global memory (" + format_size(room) +
                ", " + runtime.global_mem_source() +
                ")" + hint);
}

}  // namespace opsila
