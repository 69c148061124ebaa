#include <gtest/gtest.h>

#include "afford/rng.hpp"

using afford::KeyedRng;
using afford::Purpose;

TEST(KeyedRng, SameKeyGivesSameDraws) {
  const KeyedRng a(7, 42, Purpose::ScanNoise), b(7, 42, Purpose::ScanNoise);
  for (std::uint64_t i = 0; i < 100; ++i) EXPECT_EQ(a.bits(i), b.bits(i));
}

TEST(KeyedRng, SeedStepPurposeAndSubKeyEachChangeTheDraws) {
  const KeyedRng base(7, 42, Purpose::ScanNoise);
  EXPECT_NE(base.bits(0), KeyedRng(8, 42, Purpose::ScanNoise).bits(0));
  EXPECT_NE(base.bits(0), KeyedRng(7, 43, Purpose::ScanNoise).bits(0));
  EXPECT_NE(base.bits(0), KeyedRng(7, 42, Purpose::MoveTarget).bits(0));
  EXPECT_NE(base.bits(0), KeyedRng(7, 42, Purpose::ScanNoise, 1).bits(0));
}

TEST(KeyedRng, UniformIsInTheUnitIntervalWithMeanOneHalf) {
  const KeyedRng r(1, 0, Purpose::ActionSuccess);
  double sum = 0;
  const int n = 100000;
  for (int i = 0; i < n; ++i) {
    const double u = r.uniform(i);
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    sum += u;
  }
  EXPECT_NEAR(sum / n, 0.5, 0.005);
}

TEST(KeyedRng, UniformRangeIsRespected) {
  const KeyedRng r(3, 9, Purpose::MoveTarget);
  for (int i = 0; i < 1000; ++i) {
    const double v = r.uniform(i, 0.2, 0.8);
    ASSERT_GE(v, 0.2);
    ASSERT_LT(v, 0.8);
  }
}
