#include "device/device_buffers.h"

#include <cstdlib>
#include <cstring>

#include "device/descriptors.h"

namespace opsila {

cl::Buffer device_buffer(ClRuntime& rt, std::size_t bytes, const char* what, cl_mem_flags flags, void* host) {
  if (bytes > rt.max_alloc())
    throw ClError(std::string("buffer '") + what + "' needs " + std::to_string(bytes) +
                  " bytes, more than the device's CL_DEVICE_MAX_MEM_ALLOC_SIZE (" + std::to_string(rt.max_alloc()) +
                  " bytes" + (rt.memory_limit() ? ", " + rt.global_mem_source() : std::string()) +
                  "): use a smaller --size, --depth or --bank-capacity");
  cl_int err = CL_SUCCESS;
  cl::Buffer b(rt.context(), flags, host ? bytes : std::max<std::size_t>(bytes, 16), host, &err);
  cl_check(err, (std::string("clCreateBuffer(") + what + ", " + std::to_string(bytes) + " bytes)").c_str());
  rt.count_allocation(bytes, what);
  return b;
}

void zero_buffer(ClRuntime& rt, const cl::Buffer& b, std::size_t bytes, const char* what) {
  // Static and never written: non-blocking writes may read it at any time.
  static const unsigned char zeros[1 << 16] = {};
  for (std::size_t at = 0; at < bytes; at += sizeof zeros) {
    const std::size_t chunk = std::min(sizeof zeros, bytes - at);
    cl_check(rt.queue().enqueueWriteBuffer(b, CL_FALSE, at, chunk, zeros),
             (std::string("clEnqueueWriteBuffer(") + what + ", zeros)").c_str());
  }
}

std::shared_ptr<void> HostArray::aligned_copy(const void* from, std::size_t bytes, std::size_t alignment) {
  // aligned_alloc wants a size that is a multiple of the alignment.
  const std::size_t size = std::max<std::size_t>(alignment, (bytes + alignment - 1) / alignment * alignment);
  void* to = std::aligned_alloc(alignment, size);
  if (!to) throw std::bad_alloc();
  if (bytes) std::memcpy(to, from, bytes);
  return std::shared_ptr<void>(to, [](void* p) { std::free(p); });
}

BufferSpec kept_host_buffer(const char* name, PlanPart part, const HostArray& a, cl::Buffer* to) {
  BufferSpec s;
  s.name = name, s.part = part, s.element = a.element(), s.count = std::max<std::size_t>(1, a.count());
  s.fill = Fill::upload, s.host = a.data(), s.host_count = a.count(), s.host_kept = true, s.buffer = to;
  return s;
}

BufferSpec frame_buffer(const char* name, PlanPart part, std::size_t element, std::size_t count, Fill fill,
                        cl::Buffer* to) {
  BufferSpec s;
  s.name = name, s.part = part, s.element = element, s.count = std::max<std::size_t>(1, count);
  s.fill = fill, s.buffer = to;
  return s;
}

void PinnedHostBuffer::release() {
  // A failed unmap changes nothing for the caller: the buffer is released
  // with it, and the runtime frees both.
  if (p_) queue_.enqueueUnmapMemObject(buffer_, p_), queue_.finish();
  p_ = nullptr;
  bytes_ = 0;
  buffer_ = cl::Buffer();
}

PinnedHostBuffer::~PinnedHostBuffer() { release(); }

void PinnedHostBuffer::reserve(ClRuntime& rt, std::size_t bytes, const char* what) {
  if (p_ && bytes_ >= bytes) return;
  release();
  queue_ = rt.queue();
  cl_int err = CL_SUCCESS;
  buffer_ = cl::Buffer(rt.context(), CL_MEM_READ_WRITE | CL_MEM_ALLOC_HOST_PTR, std::max<std::size_t>(bytes, 1), nullptr,
                       &err);
  cl_check(err, (std::string("clCreateBuffer(") + what + ", CL_MEM_ALLOC_HOST_PTR)").c_str());
  p_ = queue_.enqueueMapBuffer(buffer_, CL_TRUE, CL_MAP_READ | CL_MAP_WRITE, 0, std::max<std::size_t>(bytes, 1),
                               nullptr, nullptr, &err);
  if (err != CL_SUCCESS) p_ = nullptr;
  cl_check(err, (std::string("clEnqueueMapBuffer(") + what + ")").c_str());
  bytes_ = bytes;
}

HostSharing host_sharing(ClRuntime& rt) {
  HostSharing h;
  const cl::Device& d = rt.device().device;
  cl_bool unified = CL_FALSE;
  cl_uint align_bits = 0;
  cl_check(d.getInfo(CL_DEVICE_HOST_UNIFIED_MEMORY, &unified), "clGetDeviceInfo(CL_DEVICE_HOST_UNIFIED_MEMORY)");
  cl_check(d.getInfo(CL_DEVICE_MEM_BASE_ADDR_ALIGN, &align_bits), "clGetDeviceInfo(CL_DEVICE_MEM_BASE_ADDR_ALIGN)");
  h.in_place = unified != CL_FALSE;
  // In bits; at least a pointer's alignment, as aligned_alloc needs.
  h.alignment = std::max<std::size_t>(sizeof(void*), align_bits / 8);
  return h;
}

namespace {

// An upload: used in place where the device shares host memory and the
// owner keeps the array aligned; otherwise a copy, written without waiting
// when the owner keeps the array (it outlives the write), else at once.
cl::Buffer upload_spec(ClRuntime& rt, const BufferSpec& s, const HostSharing& sharing, std::uint64_t& in_place) {
  const std::size_t bytes = s.host_count * s.element;
  const bool aligned = reinterpret_cast<std::uintptr_t>(s.host) % sharing.alignment == 0;
  if (s.host_kept && sharing.in_place && bytes > 0 && aligned) {
    in_place += bytes;
    return device_buffer(rt, bytes, s.name, CL_MEM_READ_ONLY | CL_MEM_USE_HOST_PTR, const_cast<void*>(s.host));
  }
  cl::Buffer b = device_buffer(rt, s.bytes(), s.name, CL_MEM_READ_ONLY);
  if (bytes > 0)
    cl_check(rt.queue().enqueueWriteBuffer(b, s.host_kept ? CL_FALSE : CL_TRUE, 0, bytes, s.host),
             (std::string("clEnqueueWriteBuffer(") + s.name + ")").c_str());
  return b;
}

}  // namespace

std::uint64_t allocate_buffers(ClRuntime& rt, const std::vector<BufferSpec>& table) {
  const HostSharing sharing = host_sharing(rt);
  std::uint64_t in_place = 0;
  for (const BufferSpec& s : table) {
    if (s.set) {
      s.set->allocate(rt, s.count, s.name);
    } else if (s.buffer) {
      *s.buffer = s.fill == Fill::upload ? upload_spec(rt, s, sharing, in_place)
                                         : device_buffer(rt, s.bytes(), s.name);
    }
    if (s.capacity) *s.capacity = s.count;
  }
  return in_place;
}

void zero_frame_buffers(ClRuntime& rt, const std::vector<BufferSpec>& table) {
  for (const BufferSpec& s : table)
    if (s.fill == Fill::zero && s.buffer) zero_buffer(rt, *s.buffer, s.bytes(), s.name);
}

}  // namespace opsila
