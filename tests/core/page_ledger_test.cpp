// Pages of an array read for the last time go back to the system (their
// bytes then read as zeros) once every element on them is done, and never
// before; a vector moved to a new capacity keeps its elements.
#include <gtest/gtest.h>

#include <cstdint>
#include <numeric>
#include <vector>

#include <unistd.h>

#include "core/page_ledger.h"

namespace opsila {
namespace {

struct Record {  // 56 bytes, like a scene triangle: records straddle pages
  std::uint32_t v[14];
};

TEST(PageLedger, APageGoesOnlyOnceEveryRecordOnItIsDone) {
  const std::size_t page = std::size_t(sysconf(_SC_PAGESIZE));
  std::vector<Record> a(40 * page / sizeof(Record));
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::uint32_t& x : a[i].v) x = std::uint32_t(i + 1);
  PageLedger ledger(a.data(), a.size(), sizeof(Record));
  // Every record but one in the array's middle done: the page(s) holding
  // that one keep their bytes; whole pages of done records read as zeros.
  const std::size_t kept = a.size() / 2;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (i != kept) ledger.done(i);
  ledger.release();
  for (std::uint32_t x : a[kept].v) EXPECT_EQ(x, kept + 1) << "a page with a record not done went";
  std::size_t zeroed = 0;
  for (const Record& r : a) zeroed += r.v[0] == 0 && r.v[13] == 0;
  EXPECT_GT(zeroed, a.size() / 2) << "the pages of done records were not handed back";
  ledger.done(kept);
  ledger.release();
  for (std::uint32_t x : a[kept].v) EXPECT_TRUE(x == 0 || x == kept + 1);
}

TEST(PageLedger, MovedToANewCapacityKeepsEveryElement) {
  std::vector<int> v(300000);
  std::iota(v.begin(), v.end(), 7);
  move_to_capacity(v, v.size() + v.size() / 4);
  ASSERT_EQ(v.size(), 300000u);
  EXPECT_GE(v.capacity(), 375000u);
  for (std::size_t i = 0; i < v.size(); ++i) ASSERT_EQ(v[i], int(i) + 7);
  move_to_capacity(v, 0);  // never below the size
  EXPECT_EQ(v.capacity(), v.size());
  EXPECT_EQ(v.back(), 300006);
}

}  // namespace
}  // namespace opsila
