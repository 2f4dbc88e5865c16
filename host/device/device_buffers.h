// Device buffers: checked creation, zeroing and uploads, and the buffer
// table in which the frame declares each of its buffers once (name, element
// size, count, host source, who writes it). The memory plan sums the table
// (memory_plan.h) and allocate_buffers creates and fills what it lists, so
// the two cannot disagree.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "device/cl_runtime.h"

namespace opsila {

struct DescriptorSet;

// Checked buffer creation: refuses (with the numbers) what the device cannot
// hold. `host`: with CL_MEM_USE_HOST_PTR in `flags`, the memory the buffer
// uses in place.
cl::Buffer device_buffer(ClRuntime& rt, std::size_t bytes, const char* what, cl_mem_flags flags = CL_MEM_READ_WRITE,
                         void* host = nullptr);

// Sets the first `bytes` of a buffer to zero with plain writes (enqueued, not
// waited for). Not clEnqueueFillBuffer: Oclgrind's uninitialized-value check
// does not count a fill as a write, and the kernels must stay checkable
// (docs/RELIABILITY.md).
void zero_buffer(ClRuntime& rt, const cl::Buffer& b, std::size_t bytes, const char* what);

template <typename T, typename A>
cl::Buffer upload(ClRuntime& rt, const std::vector<T, A>& v, const char* what) {
  cl::Buffer b = device_buffer(rt, std::max<std::size_t>(1, v.size()) * sizeof(T), what);
  if (!v.empty())
    cl_check(rt.queue().enqueueWriteBuffer(b, CL_TRUE, 0, v.size() * sizeof(T), v.data()),
             (std::string("clEnqueueWriteBuffer(") + what + ")").c_str());
  return b;
}

// Host memory that a device's copy engine reads and writes directly: a
// CL_MEM_ALLOC_HOST_PTR buffer, mapped once for its whole life. A read
// from a discrete GPU into it is one transfer; into ordinary (pageable)
// memory, or through a map of the device buffer, the driver stages the
// bytes through pinned pages of its own on every call. Unmapped and
// released with the object.
class PinnedHostBuffer {
 public:
  PinnedHostBuffer() = default;
  ~PinnedHostBuffer();
  PinnedHostBuffer(const PinnedHostBuffer&) = delete;
  PinnedHostBuffer& operator=(const PinnedHostBuffer&) = delete;
  // At least `bytes` (kept when already as large). Throws ClError.
  void reserve(ClRuntime& rt, std::size_t bytes, const char* what);
  void* data() const { return p_; }

 private:
  void release();
  cl::CommandQueue queue_;
  cl::Buffer buffer_;
  void* p_ = nullptr;
  std::size_t bytes_ = 0;
};

// A large host array that a device buffer may use in place: on a device
// that shares host memory (CL_DEVICE_HOST_UNIFIED_MEMORY, PoCL on a CPU),
// CL_MEM_USE_HOST_PTR spares a second copy of the bank arrays, but only at
// the device's base-address alignment. adopt() takes the vector as it is
// when it is aligned (or alignment is 1: the bank arrays are made aligned,
// partition/bank_array.h), else moves its bytes into an aligned block and
// frees the vector at once. Whoever holds the HostArray
// must keep it as long as the buffer made from it.
class HostArray {
 public:
  HostArray() = default;
  template <typename T, typename A>
  static HostArray adopt(std::vector<T, A>&& v, std::size_t alignment) {
    HostArray a;
    a.count_ = v.size();
    a.element_ = sizeof(T);
    if (alignment <= 1 || reinterpret_cast<std::uintptr_t>(v.data()) % alignment == 0) {
      auto kept = std::make_shared<std::vector<T, A>>(std::move(v));
      a.data_ = kept->data();
      a.owner_ = std::move(kept);
    } else {
      a.owner_ = aligned_copy(v.data(), v.size() * sizeof(T), alignment);
      a.data_ = a.owner_.get();
      std::vector<T, A>().swap(v);
    }
    return a;
  }
  const void* data() const { return data_; }
  std::size_t count() const { return count_; }
  std::size_t element() const { return element_; }
  bool empty() const { return count_ == 0; }

 private:
  static std::shared_ptr<void> aligned_copy(const void* from, std::size_t bytes, std::size_t alignment);
  std::shared_ptr<void> owner_;
  const void* data_ = nullptr;
  std::size_t count_ = 0, element_ = 1;
};

// Where a buffer's bytes count in the memory plan (device/memory_plan.h).
enum class PlanPart { scene, image, descriptors, other };

// How a buffer gets its contents.
enum class Fill {
  upload,  // the host array `host`, once, when it is allocated (kernels only read it)
  zero,    // zeros before every frame: sums and counters
  device,  // the kernels write it before they read it
};

// One device buffer of the frame, declared once.
struct BufferSpec {
  const char* name = "";              // in errors, the plan and the tests
  PlanPart part = PlanPart::other;
  std::size_t element = 0, count = 0;  // bytes per element, elements (at least 1)
  Fill fill = Fill::device;
  const void* host = nullptr;          // Fill::upload: host_count elements
  std::size_t host_count = 0;
  // Fill::upload: the owner keeps `host` as long as the buffer, so a device
  // that shares host memory may use it in place (CL_MEM_USE_HOST_PTR).
  bool host_kept = false;
  // Where its owner keeps it: a buffer, or a descriptor vector (records and
  // destinations, element = DescriptorSet::kSlotBytes). Neither: the owner
  // allocates it itself (the scatter's per-PE tables, at its construction)
  // and the table only plans it.
  cl::Buffer* buffer = nullptr;
  DescriptorSet* set = nullptr;
  std::size_t* capacity = nullptr;  // set to `count`: the owner grows it beyond on demand
  std::uint64_t bytes() const { return std::uint64_t(element) * count; }
};

// An upload of a host vector (one element of placeholder when it is empty).
template <typename T, typename A>
BufferSpec host_buffer(const char* name, PlanPart part, const std::vector<T, A>& v, cl::Buffer* to) {
  BufferSpec s;
  s.name = name, s.part = part, s.element = sizeof(T), s.count = std::max<std::size_t>(1, v.size());
  s.fill = Fill::upload, s.host = v.data(), s.host_count = v.size(), s.buffer = to;
  return s;
}
// An upload of a HostArray that its owner keeps as long as the buffer.
BufferSpec kept_host_buffer(const char* name, PlanPart part, const HostArray& a, cl::Buffer* to);
// A buffer the kernels fill (Fill::device) or that is zeroed every frame.
BufferSpec frame_buffer(const char* name, PlanPart part, std::size_t element, std::size_t count, Fill fill,
                        cl::Buffer* to);

// Whether buffers of this device may use host memory in place, and at what
// alignment (CL_DEVICE_HOST_UNIFIED_MEMORY, CL_DEVICE_MEM_BASE_ADDR_ALIGN).
struct HostSharing {
  bool in_place = false;
  std::size_t alignment = 1;  // bytes
};
HostSharing host_sharing(ClRuntime& rt);

// Creates every buffer the table gives a place (and fills the uploads);
// returns how many bytes of uploads the device uses in place.
std::uint64_t allocate_buffers(ClRuntime& rt, const std::vector<BufferSpec>& table);
// Zeroes the table's Fill::zero buffers (enqueued, not waited for).
void zero_frame_buffers(ClRuntime& rt, const std::vector<BufferSpec>& table);

}  // namespace opsila
