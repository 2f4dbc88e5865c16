#include "core/page_ledger.h"

#include <algorithm>

#include <sys/mman.h>
#include <unistd.h>

namespace opsila {

PageLedger::PageLedger(const void* data, std::size_t count, std::size_t size)
    : begin_(reinterpret_cast<std::uintptr_t>(data)), size_(size) {
  page_ = std::uintptr_t(sysconf(_SC_PAGESIZE));
  end_ = begin_ + count * size;
  if (count == 0) return;
  left_.assign((end_ - 1) / page_ - begin_ / page_ + 1, 0);
  for (std::size_t i = 0; i < count; ++i)
    for (std::uintptr_t p = first_page(i); p <= last_page(i); ++p) ++left_[p - begin_ / page_];
}

void PageLedger::done(std::size_t i) {
  for (std::uintptr_t p = first_page(i); p <= last_page(i); ++p)
    if (--left_[p - begin_ / page_] == 0) full_.push_back(p);
}

void PageLedger::release() {
  std::sort(full_.begin(), full_.end());
  const std::uintptr_t lo = (begin_ + page_ - 1) / page_, hi = end_ / page_;  // whole pages inside
  for (std::size_t k = 0; k < full_.size();) {
    std::size_t j = k + 1;
    while (j < full_.size() && full_[j] == full_[j - 1] + 1) ++j;  // a run of adjacent pages: one call
    const std::uintptr_t a = std::max<std::uintptr_t>(full_[k], lo), b = std::min<std::uintptr_t>(full_[j - 1] + 1, hi);
    if (b > a) madvise(reinterpret_cast<void*>(a * page_), (b - a) * page_, MADV_DONTNEED);  // advice: a failure only keeps them
    k = j;
  }
  full_.clear();
}

}  // namespace opsila
