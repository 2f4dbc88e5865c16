// An array read for the last time in an order of its own (the partition's
// clusters, the exchange's destinations) gives its memory back as it goes:
// a page is handed back to the system once every element on it has been
// read, so the array shrinks while what is made from it grows, instead of
// both being whole at once (the preparation's peak).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace opsila {

class PageLedger {
 public:
  // The array of `count` elements of `size` bytes at `data`.
  PageLedger(const void* data, std::size_t count, std::size_t size);
  // Element i has been read for the last time.
  void done(std::size_t i);
  // Hands back the pages whose every element is done (whole pages inside
  // the array only: its allocation's bookkeeping stays untouched). Their
  // bytes read as zeros after; the array is freed by its owner as usual.
  void release();

 private:
  // The pages element i lies on (it may straddle two).
  std::uintptr_t first_page(std::size_t i) const { return (begin_ + i * size_) / page_; }
  std::uintptr_t last_page(std::size_t i) const { return (begin_ + (i + 1) * size_ - 1) / page_; }
  std::uintptr_t begin_ = 0, end_ = 0, page_ = 4096;
  std::size_t size_ = 1;
  std::vector<std::uint16_t> left_;  // elements not yet done, per page
  std::vector<std::size_t> full_;    // pages done since the last release
};

// Gives v a new capacity (at least its size) through a new array: the
// elements are moved a chunk at a time and the old array's pages handed
// back as they go, so that growing a vector that holds most of a process's
// memory (a rank's share of a scene) never holds two whole copies.
template <class T>
void move_to_capacity(std::vector<T>& v, std::size_t capacity) {
  std::vector<T> to;
  to.reserve(std::max(capacity, v.size()));
  PageLedger old(v.data(), v.size(), sizeof(T));
  constexpr std::size_t kChunk = std::size_t(1) << 16;
  for (std::size_t i = 0; i < v.size(); i += kChunk) {
    const std::size_t e = std::min(v.size(), i + kChunk);
    to.insert(to.end(), v.begin() + std::ptrdiff_t(i), v.begin() + std::ptrdiff_t(e));
    for (std::size_t k = i; k < e; ++k) old.done(k);
    old.release();
  }
  v.swap(to);
}

}  // namespace opsila
