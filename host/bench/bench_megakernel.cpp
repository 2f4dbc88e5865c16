// The replicated-scene megakernel baseline: host side of kernels/baselines/megakernel.cl.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "bench/bench.h"
#include "core/camera.h"
#include "core/fixed_point.h"
#include "opsila_shared.h"
#include "machine/partition.h"
#include "machine/kernel_args.h"
#include "machine/renderer.h"

namespace opsila {

BaselineImage render_megakernel(const Scene& scene, ClRuntime& rt, int tile) {
  check_kernel_limits(scene);
  const std::size_t npix = std::size_t(scene.width) * scene.height;
  BaselineImage out;
  out.width = scene.width;
  out.height = scene.height;

  // One PE: bank 0 is the whole scene under one BVH (clusters on top).
  auto t_build = std::chrono::steady_clock::now();
  BankedScene bs = partition_scene(scene, 1);
  FrameParams fp = frame_params(scene, bs, 0);
  out.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_build).count();

  rt.program();  // compile before timing
  // kernels/baselines/megakernel.cl: frame, bank nodes and facets,
  // materials, lights, surface, root node, sample grid side and offsets,
  // pixels, pixel sums, ray counts, item buffer.
  using Buf = cl::Buffer;
  KernelBinding<FrameParams, Buf, Buf, Buf, Buf, SurfaceBuffers, int, int, Buf, int, int, Buf, Buf, Buf> mega(
      rt, "megakernel", KernelProgram::baselines);
  cl::Kernel& k = mega.kernel();
  cl::CommandQueue& q = rt.queue();

  auto t0 = std::chrono::steady_clock::now();
  cl::Buffer b_tris = upload(rt, bs.triangles, "facets");
  cl::Buffer b_nodes = upload(rt, bs.nodes, "BVH nodes");
  cl::Buffer b_mats = upload(rt, bs.materials, "materials");
  std::vector<Light> lights = bs.lights;
  if (lights.empty()) lights.push_back(Light{});
  cl::Buffer b_lights = upload(rt, lights, "lights");
  const SurfaceBuffers surface = upload_surface(rt, bs);
  cl::Buffer b_accum = device_buffer(rt, npix * 3 * sizeof(cl_long), "pixel sums");
  cl::Buffer b_counts = device_buffer(rt, npix * sizeof(cl_uint4), "ray counts");
  cl::Buffer b_items = device_buffer(rt, npix * sizeof(cl_int2), "item buffer");
  cl::Buffer b_offsets = upload(rt, sample_offsets(scene.spp), "sample offsets");

  std::vector<LaunchRecord> launches;
  Launcher launch(rt, launches);
  // One fixed work-group size, so a driver that specialises kernels per size
  // (PoCL) compiles this one once.
  std::size_t local = k.getWorkGroupInfo<CL_KERNEL_WORK_GROUP_SIZE>(rt.device().device);
  local = std::min<std::size_t>(local, 64);
  while (local & (local - 1)) local &= local - 1;  // a power of two, dividing the rounded global size
  local = std::max<std::size_t>(local, 1);
  tile = std::max(1, tile);
  for (std::size_t begin = 0; begin < npix; begin += tile) {
    int count = static_cast<int>(std::min<std::size_t>(tile, npix - begin));
    mega.bind(fp, b_nodes, b_tris, b_mats, b_lights, surface, bs.pes[0].node_begin, spp_side(scene.spp), b_offsets,
              static_cast<int>(begin), count, b_accum, b_counts, b_items);
    launch.run(k, "megakernel", round_up(count, 64), local, -1);
  }
  std::vector<cl_long> accum(npix * 3);
  std::vector<cl_uint4> counts(npix);
  out.item_buffer.resize(npix * 2);
  launch.check(q.enqueueReadBuffer(b_accum, CL_TRUE, 0, accum.size() * sizeof(cl_long), accum.data()),
               "clEnqueueReadBuffer(megakernel pixel sums)");
  launch.check(q.enqueueReadBuffer(b_counts, CL_TRUE, 0, counts.size() * sizeof(cl_uint4), counts.data()),
               "clEnqueueReadBuffer(megakernel ray counts)");
  launch.check(q.enqueueReadBuffer(b_items, CL_TRUE, 0, npix * sizeof(cl_int2), out.item_buffer.data()),
               "clEnqueueReadBuffer(megakernel item buffer)");
  launch.check(q.finish(), "clFinish");
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  launch.harvest();
  for (const LaunchRecord& r : launches) out.kernel_seconds += r.seconds;

  // Pixel sums -> floats exactly as the renderer converts its fixed point.
  out.rgb.resize(npix * 3);
  for (std::size_t i = 0; i < npix * 3; ++i)
    out.rgb[i] = from_fixed(static_cast<std::uint64_t>(accum[i]), scene.spp);  // >= 0: add_sat
  out.rays.primary = npix * static_cast<std::size_t>(scene.spp);
  for (const cl_uint4& c : counts) {
    out.rays.secondary += c.s[0];
    out.rays.shadow += c.s[1];
    out.triangle_tests += c.s[2];
    out.box_tests += c.s[3];
  }
  return out;
}

}  // namespace opsila
