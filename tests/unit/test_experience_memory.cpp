// The experience memory for replay: bounded, oldest out first, and sampled by
// its key alone.
#include <gtest/gtest.h>

#include <set>
#include <stdexcept>
#include <vector>

#include "predictors/experience_memory.hpp"

namespace afford {
namespace {

Experience numbered(int n) {
  Experience e;
  e.action = n % kNumActions;
  e.before_x = n;
  return e;
}

TEST(ExperienceMemory, HoldsAtMostItsCapacityAndDropsTheOldestFirst) {
  ExperienceMemory m(3);
  for (int n = 0; n < 5; ++n) m.add(numbered(n));
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(m.at(0).before_x, 2);  // 0 and 1 went first
  EXPECT_EQ(m.at(1).before_x, 3);
  EXPECT_EQ(m.at(2).before_x, 4);
  EXPECT_THROW(m.at(3), std::out_of_range);
}

TEST(ExperienceMemory, SamplesAreKeyedBySeedAndStep) {
  ExperienceMemory m(100);
  for (int n = 0; n < 100; ++n) m.add(numbered(n));
  EXPECT_EQ(m.sample(1, 50, 8), m.sample(1, 50, 8));
  EXPECT_NE(m.sample(1, 50, 8), m.sample(1, 51, 8));
  EXPECT_NE(m.sample(1, 50, 8), m.sample(2, 50, 8));
  // A longer sample begins with the shorter one: a count does not reshuffle.
  const auto four = m.sample(1, 50, 4), eight = m.sample(1, 50, 8);
  EXPECT_EQ(std::vector<std::size_t>(eight.begin(), eight.begin() + 4), four);
}

TEST(ExperienceMemory, SamplesCoverTheMemoryUniformly) {
  ExperienceMemory m(10);
  for (int n = 0; n < 10; ++n) m.add(numbered(n));
  std::vector<int> hits(10);
  for (std::int64_t step = 0; step < 2000; ++step)
    for (std::size_t i : m.sample(3, step, 5)) ++hits.at(i);
  for (int h : hits) EXPECT_NEAR(h / 10000.0, 0.1, 0.015);
}

TEST(ExperienceMemory, AnEmptyMemorySamplesNothingAndNoCapacityIsRefused) {
  ExperienceMemory m(4);
  EXPECT_TRUE(m.sample(1, 1, 3).empty());
  EXPECT_THROW(ExperienceMemory(0), std::invalid_argument);
}

}  // namespace
}  // namespace afford
