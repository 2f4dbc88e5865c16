// Times tinybvh's OpenCL traversal kernels on the rays of a file written by
// `opsila bench --rays-out` (docs/BENCHMARKS.md, "The rays file") and checks
// each answer (hit or miss, blocked or not) against opsila's. Built and run
// by tools/tinybvh/compare.sh; not part of opsila.
//   harness FILE.rays TINYBVH_DIR [passes]
#define TINYBVH_IMPLEMENTATION
#include "tiny_bvh.h"

#define CL_TARGET_OPENCL_VERSION 300
#include <CL/cl.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace {

void check(cl_int err, const char* what) {
  if (err == CL_SUCCESS) return;
  std::fprintf(stderr, "harness: %s failed (%d)\n", what, err);
  std::exit(1);
}

// tinybvh's GPU ray: origin, direction, reciprocal, hit (16 bytes each).
struct GpuRay {
  float o[4], d[4], rd[4], hit[4];
};

struct Workload {
  std::vector<tinybvh::bvhvec4> verts;  // three a triangle
  std::vector<GpuRay> nearest, any;
  std::vector<std::int32_t> nearest_hit, any_blocked;  // opsila's answers
};

// tinybvh has no tmin: a ray starts at origin + tmin * direction.
std::vector<GpuRay> gpu_rays(const float* f, std::size_t n) {
  std::vector<GpuRay> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    const float *o = f + 8 * i, *d = o + 4;
    GpuRay& r = out[i];
    for (int k = 0; k < 3; ++k) {
      r.o[k] = o[k] + o[3] * d[k];
      r.d[k] = d[k];
      r.rd[k] = d[k] != 0 ? 1 / d[k] : std::copysign(1e30f, d[k]);
    }
    r.o[3] = 1, r.rd[3] = 0;
    r.d[3] = std::isinf(d[3]) ? 1e30f : d[3] - o[3];
    std::memset(r.hit, 0, sizeof r.hit);
  }
  return out;
}

Workload read_workload(const char* path) {
  std::ifstream in(path, std::ios::binary);
  const std::string b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::uint32_t h[4];  // version, triangles, nearest-hit rays, any-hit rays
  if (b.size() < 24 || b.compare(0, 8, "OPSILARY") != 0) {
    std::fprintf(stderr, "harness: %s is not a rays file\n", path);
    std::exit(1);
  }
  std::memcpy(h, b.data() + 8, sizeof h);
  const std::size_t t = h[1], n = h[2], a = h[3];
  if (b.size() != 24 + 4 * (9 * t + 9 * (n + a))) {
    std::fprintf(stderr, "harness: %s: sizes disagree with its header\n", path);
    std::exit(1);
  }
  const float* f = reinterpret_cast<const float*>(b.data() + 24);
  Workload w;
  for (std::size_t i = 0; i < 3 * t; ++i) w.verts.emplace_back(f[3 * i], f[3 * i + 1], f[3 * i + 2], 0.0f);
  w.nearest = gpu_rays(f + 9 * t, n);
  w.any = gpu_rays(f + 9 * t + 8 * n, a);
  const std::int32_t* ans = reinterpret_cast<const std::int32_t*>(f + 9 * t + 8 * (n + a));
  w.nearest_hit.assign(ans, ans + n);
  w.any_blocked.assign(ans + n, ans + n + a);
  return w;
}

struct Cl {
  cl_device_id device{};
  cl_context context{};
  cl_command_queue queue{};
  cl_program program{};

  Cl(const std::string& tinybvh_dir, const std::string& here) {
    cl_platform_id platform;
    check(clGetPlatformIDs(1, &platform, nullptr), "clGetPlatformIDs");
    check(clGetDeviceIDs(platform, CL_DEVICE_TYPE_ALL, 1, &device, nullptr), "clGetDeviceIDs");
    cl_int err;
    context = clCreateContext(nullptr, 1, &device, nullptr, nullptr, &err);
    check(err, "clCreateContext");
    const cl_queue_properties props[] = {CL_QUEUE_PROPERTIES, CL_QUEUE_PROFILING_ENABLE, 0};
    queue = clCreateCommandQueueWithProperties(context, device, props, &err);
    check(err, "clCreateCommandQueueWithProperties");
    const char* src = "#include \"harness.cl\"\n";
    program = clCreateProgramWithSource(context, 1, &src, nullptr, &err);
    check(err, "clCreateProgramWithSource");
    // tinybvh's own options (tiny_ocl.h).
    const std::string opts = "-I" + here + " -I" + tinybvh_dir +
                             " -cl-std=CL2.0 -cl-strict-aliasing -cl-fast-relaxed-math -cl-single-precision-constant";
    if (clBuildProgram(program, 1, &device, opts.c_str(), nullptr, nullptr) != CL_SUCCESS) {
      static char log[1 << 16];
      clGetProgramBuildInfo(program, device, CL_PROGRAM_BUILD_LOG, sizeof log, log, nullptr);
      std::fprintf(stderr, "harness: build failed:\n%s\n", log);
      std::exit(1);
    }
  }
  cl_mem buffer(const void* p, std::size_t bytes) {
    cl_int err;
    cl_mem m = clCreateBuffer(context, CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, bytes, const_cast<void*>(p), &err);
    check(err, "clCreateBuffer");
    return m;
  }
};

// Median kernel seconds of `passes` runs after one warm-up, over whole
// work-groups of 64 (tinybvh's batch kernels have no bound), and the share
// of answers that agree with opsila's.
void time_kernel(Cl& cl, const char* layout, const char* kernel, std::vector<cl_mem> args, std::vector<GpuRay> rays,
                 const std::vector<std::int32_t>& opsila, bool nearest, int passes) {
  cl_int err;
  cl_kernel k = clCreateKernel(cl.program, kernel, &err);
  check(err, kernel);
  const std::size_t n = rays.size() / 64 * 64, local = 64;
  cl_mem b = cl.buffer(rays.data(), std::max<std::size_t>(n, 1) * sizeof(GpuRay));
  args.push_back(b);
  for (std::size_t i = 0; i < args.size(); ++i) check(clSetKernelArg(k, i, sizeof(cl_mem), &args[i]), "clSetKernelArg");
  std::vector<double> seconds;
  for (int p = 0; p <= passes && n > 0; ++p) {
    cl_event ev;
    check(clEnqueueNDRangeKernel(cl.queue, k, 1, nullptr, &n, &local, 0, nullptr, &ev), kernel);
    check(clWaitForEvents(1, &ev), "clWaitForEvents");
    cl_ulong t0, t1;
    clGetEventProfilingInfo(ev, CL_PROFILING_COMMAND_START, sizeof t0, &t0, nullptr);
    clGetEventProfilingInfo(ev, CL_PROFILING_COMMAND_END, sizeof t1, &t1, nullptr);
    clReleaseEvent(ev);
    if (p > 0) seconds.push_back((t1 - t0) * 1e-9);
  }
  check(clEnqueueReadBuffer(cl.queue, b, CL_TRUE, 0, n * sizeof(GpuRay), rays.data(), 0, nullptr, nullptr),
        "clEnqueueReadBuffer");
  std::size_t agree = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const bool theirs = nearest ? rays[i].hit[0] < 1e29f : rays[i].hit[0] != 0;
    agree += theirs == (nearest ? opsila[i] >= 0 : opsila[i] == 1);
  }
  std::sort(seconds.begin(), seconds.end());
  const double med = seconds.empty() ? 0 : seconds[seconds.size() / 2];
  std::printf("%-9s %-12s %9zu rays  %.4f s  %6.2f Mrays/s  agrees with opsila on %.4f%%\n", layout,
              nearest ? "nearest hit" : "any hit", n, med, med > 0 ? n / med * 1e-6 : 0.0,
              n ? 100.0 * agree / n : 100.0);
  clReleaseMemObject(b);
  clReleaseKernel(k);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: harness FILE.rays TINYBVH_DIR [passes]\n");
    return 2;
  }
  const int passes = argc > 3 ? std::max(1, std::atoi(argv[3])) : 9;
  std::string here = argv[0];
  here = here.find('/') == std::string::npos ? "." : here.substr(0, here.rfind('/'));
  const Workload w = read_workload(argv[1]);
  const auto tris = static_cast<std::uint32_t>(w.verts.size() / 3);
  std::printf("%u triangles, %zu nearest-hit rays, %zu any-hit rays; median of %d runs after one\n", tris,
              w.nearest.size(), w.any.size(), passes);
  Cl cl(argv[2], here);

  tinybvh::BVH4_GPU b4;
  b4.BuildHQ(w.verts.data(), tris);
  cl_mem n4 = cl.buffer(b4.bvh4Data, b4.usedBlocks * sizeof(tinybvh::bvhvec4));
  time_kernel(cl, "BVH4_GPU", "batch_gpu4way", {n4}, w.nearest, w.nearest_hit, true, passes);
  time_kernel(cl, "BVH4_GPU", "occluded_gpu4way", {n4}, w.any, w.any_blocked, false, passes);

  tinybvh::BVH_GPU b2;
  b2.BuildHQ(w.verts.data(), tris);
  cl_mem n2 = cl.buffer(b2.bvhNode, b2.usedNodes * sizeof(tinybvh::BVH_GPU::BVHNode));
  cl_mem i2 = cl.buffer(b2.bvh.primIdx, b2.bvh.idxCount * sizeof(std::uint32_t));
  cl_mem v2 = cl.buffer(w.verts.data(), w.verts.size() * sizeof(tinybvh::bvhvec4));
  time_kernel(cl, "BVH_GPU", "batch_ailalaine", {n2, i2, v2}, w.nearest, w.nearest_hit, true, passes);
  time_kernel(cl, "BVH_GPU", "occluded_ailalaine", {n2, i2, v2}, w.any, w.any_blocked, false, passes);

  tinybvh::BVH8_CWBVH b8;
  b8.BuildHQ(w.verts.data(), tris);
  cl_mem n8 = cl.buffer(b8.bvh8Data, b8.usedBlocks * sizeof(tinybvh::bvhvec4));
  cl_mem t8 = cl.buffer(b8.bvh8Tris, b8.idxCount * 3 * sizeof(tinybvh::bvhvec4));
  time_kernel(cl, "CWBVH", "batch_cwbvh", {n8, t8}, w.nearest, w.nearest_hit, true, passes);
  time_kernel(cl, "CWBVH", "occluded_cwbvh", {n8, t8}, w.any, w.any_blocked, false, passes);
  return 0;
}
