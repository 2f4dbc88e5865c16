// A large array put in a new order without a copy of it: the preparation's
// peak memory is a few arrays of the scene's size, and a copy made only to
// reorder one would be one more.
#pragma once

#include <cstddef>
#include <stdexcept>
#include <vector>

#include "opsila_shared.h"

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

// new[i] = old[order[i]] for a bank's facets and the arrays that follow
// them (from position `base`), in place: a copy of a bank's facets would be
// 48 bytes a facet at the build's peak.
inline void permute_bank_facets(const std::vector<int>& order, BankTriangle* tris,
                                const std::vector<std::vector<int>*>& follow, std::size_t base) {
  struct Slot {
    BankTriangle t;
    int value[2];
  };
  std::vector<int*> v;  // the following arrays, at most two (FacetMaps)
  for (std::vector<int>* f : follow)
    if (!f->empty()) v.push_back(f->data() + base);
  if (v.size() > 2) throw std::logic_error("build_bank_bvh: more arrays follow the facets than it moves");
  const auto get = [&](std::size_t i) { return Slot{tris[i], {v.size() > 0 ? v[0][i] : 0, v.size() > 1 ? v[1][i] : 0}}; };
  permute_in_place(order, get, [&](std::size_t i, const Slot& s) {
    tris[i] = s.t;
    for (std::size_t a = 0; a < v.size(); ++a) v[a][i] = s.value[a];
  });
}

}  // namespace opsila
