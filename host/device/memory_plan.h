// The memory plan of a frame: how many descriptors are in flight, and
// what the device must hold before the first launch: the sum of the
// frame's buffer table (device/device_buffers.h, the table itself in
// frame_buffers.cpp). The renderer sizes its banks with it, halving n until
// the plan fits the device.
#pragma once

#include <cstddef>
#include <cstdint>

#include <vector>

#include "device/device_buffers.h"

namespace opsila {

// Device memory a rank's banks take per triangle of its share: the facet
// records (48 bytes) and the bank BVH nodes (26-32 at 16 PEs), measured 79-90
// with the frame's other buffers (docs/DISTRIBUTED.md, "Cost model"). Read by the check before the partition
// (prepare/scene_limits.h); the exact plan follows the bank build.
constexpr std::uint64_t kDeviceBytesPerTriangle = 96;

// Device memory that a frame allocates before the first launch, by part.
struct DevicePlan {
  std::uint64_t scene = 0, image = 0, descriptors = 0, other = 0;
  std::uint64_t total() const { return scene + image + descriptors + other; }
};

// The descriptors of one frame: F = P * n bank slots in flight (P: the PEs
// with banks on this device, a group of them with several MPI ranks), G SPMD
// work-groups at most, each work-item with S output places, and two pools.
struct FlightPlan {
  std::size_t slots = 0, group_size = 1, groups = 0, outputs = 0, inject = 0, pool = 0;
  FlightPlan(int P, int n, std::size_t wg, int S);
};

DevicePlan plan_of(const std::vector<BufferSpec>& table);

}  // namespace opsila
