// The limits a scene meets before anything of it is built: the triangles
// one rank's host memory holds while preparing (scene/triangle_limit.h),
// agreed by every rank, and a first look at whether this rank's share fits
// its device (the exact check follows the bank build: frame_prepare.cpp).
#pragma once

#include <cstdint>

#include "device/cl_runtime.h"
#include "mpi/ranks.h"
#include "scene/scene.h"

namespace opsila {

// The smallest of the ranks' host memories, with where it came from, on
// every rank: each rank reads the whole scene's budget, so all must refuse
// or take it alike.
HostMemory agree_host_memory(Ranks& ranks, const HostMemory& mine);

// One rank's triangle limit: `flag_bytes` (--host-memory) when nonzero,
// else the memory available on this host shared by the ranks that run on
// it, agreed over the ranks. Throws OtherRankFailed when another rank
// failed before it (Ranks::checkpoint).
TriangleLimit host_triangle_limit(Ranks& ranks, std::uint64_t flag_bytes);

// Throws ClError, naming the scene file, when this rank's share of the
// scene's triangles clearly needs more than the device's global memory
// (kDeviceBytesPerTriangle), before the partition builds anything.
void check_device_room(const Scene& scene, const std::string& path, Ranks& ranks, const ClRuntime& runtime);

}  // namespace opsila
