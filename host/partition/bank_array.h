// The bank arrays (facets, BVH nodes) are made where a device that shares
// host memory can read them in place: CL_MEM_USE_HOST_PTR wants the
// device's base-address alignment (PoCL and Rusticl on a CPU: 128 bytes).
// A plain std::vector is 16-byte aligned, so handing one to such a device
// meant a copy of the whole array (8.4 M facets: 0.4 GB) before the first
// frame. A device asking for more still gets the copy
// (HostArray::adopt, device/device_buffers.h).
#pragma once

#include <cstddef>
#include <new>
#include <vector>

namespace opsila {

constexpr std::size_t kBankArrayAlignment = 128;

template <typename T>
struct BankAllocator {
  using value_type = T;
  BankAllocator() = default;
  template <typename U>
  BankAllocator(const BankAllocator<U>&) {}
  T* allocate(std::size_t n) {
    return static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t(kBankArrayAlignment)));
  }
  void deallocate(T* p, std::size_t) { ::operator delete(p, std::align_val_t(kBankArrayAlignment)); }
  template <typename U>
  bool operator==(const BankAllocator<U>&) const { return true; }
  template <typename U>
  bool operator!=(const BankAllocator<U>&) const { return false; }
};

template <typename T>
using BankArray = std::vector<T, BankAllocator<T>>;

}  // namespace opsila
