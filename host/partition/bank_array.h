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
#include <type_traits>
#include <utility>
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
  // resize() and emplace_back() leave a new element as it is (the bank
  // builders write every element before anything reads it): value-
  // initialising would touch every page of a large array at once, before
  // its contents arrive (the partition fills the facets a batch at a time
  // as the scene's copy gives its pages back).
  template <typename U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible<U>::value) {
    ::new (static_cast<void*>(p)) U;
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
  template <typename U>
  bool operator==(const BankAllocator<U>&) const { return true; }
  template <typename U>
  bool operator!=(const BankAllocator<U>&) const { return false; }
};

template <typename T>
using BankArray = std::vector<T, BankAllocator<T>>;

}  // namespace opsila
