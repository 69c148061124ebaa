// Random affordance tables: 0/1 entries, every row and column mixed, the
// same table for the same (seed, index), and unbiased over many tables.
#include <gtest/gtest.h>

#include <set>
#include <stdexcept>
#include <vector>

#include "afford/tables.hpp"

namespace afford {
namespace {

TEST(RandomTables, EntriesAreZeroOrOneAndEveryRowAndColumnIsMixed) {
  for (std::int64_t i = 0; i < 500; ++i) {
    const AffordanceTable t = randomTable(7, i, 9);
    ASSERT_EQ(t.size(), 9u);
    for (const auto& row : t)
      for (double v : row) EXPECT_TRUE(v == 0.0 || v == 1.0) << v;
    EXPECT_TRUE(mixed(t)) << "table " << i;
  }
}

TEST(RandomTables, TheSameSeedAndIndexGiveTheSameTableAndOthersDiffer) {
  EXPECT_EQ(randomTable(3, 5, 9), randomTable(3, 5, 9));
  std::set<AffordanceTable> seen;
  for (std::int64_t seed : {1, 2})
    for (std::int64_t i = 0; i < 50; ++i) seen.insert(randomTable(seed, i, 9));
  EXPECT_GT(seen.size(), 95u);  // 2^36 tables: repeats would be a keying mistake
}

TEST(RandomTables, OnesAndZerosAreEquallyLikelyInEveryCell) {
  std::vector<std::array<int, kNumActions>> ones(9);
  const int n = 4000;
  for (std::int64_t i = 0; i < n; ++i) {
    const AffordanceTable t = randomTable(11, i, 9);
    for (std::size_t o = 0; o < 9; ++o)
      for (std::size_t a = 0; a < kNumActions; ++a) ones[o][a] += t[o][a] == 1.0;
  }
  for (std::size_t o = 0; o < 9; ++o)
    for (std::size_t a = 0; a < kNumActions; ++a)
      EXPECT_NEAR(ones[o][a] / static_cast<double>(n), 0.5, 0.04) << "object " << o << " action " << a;
}

TEST(RandomTables, MixedTellsUnmixedTablesApart) {
  AffordanceTable t = {{1, 0, 1, 0}, {0, 1, 0, 1}};
  EXPECT_TRUE(mixed(t));
  t[0] = {1, 1, 1, 1};  // an object affording everything
  EXPECT_FALSE(mixed(t));
  t = {{1, 0, 1, 0}, {1, 1, 0, 0}};  // move afforded by every object
  EXPECT_FALSE(mixed(t));
}

TEST(RandomTables, FewerThanTwoObjectsAreRefused) {
  EXPECT_THROW(randomTable(1, 0, 1), std::invalid_argument);
}

}  // namespace
}  // namespace afford
