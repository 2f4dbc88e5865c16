// A large array put in a new order without a copy of it: the preparation's
// peak memory is a few arrays of the scene's size, and a copy made only to
// reorder one would be one more.
#pragma once

#include <cstddef>
#include <vector>

namespace opsila {

// Puts old element from[i] at position i for every i (`from`: a
// permutation of 0 .. n-1), in place along the permutation's cycles: each
// position is written once, with one element set aside per cycle. get(i)
// reads what position i holds (by value), set(i, v) writes it.
template <class Get, class Set>
void permute_in_place(const std::vector<int>& from, Get get, Set set) {
  std::vector<bool> done(from.size(), false);
  for (std::size_t k = 0; k < from.size(); ++k) {
    if (done[k]) continue;
    auto first = get(k);
    std::size_t j = k;
    while (std::size_t(from[j]) != k) {
      const std::size_t next = std::size_t(from[j]);
      set(j, get(next));
      done[j] = true;
      j = next;
    }
    set(j, first);
    done[j] = true;
  }
}

}  // namespace opsila
