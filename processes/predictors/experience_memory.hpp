// A bounded memory of past experiences, for experience replay (the paper's
// section 5 proposal, issue 11): "replay of past experience that would
// intermix experience related to the different objects". Not used unless
// replay is configured; the paper's experiments do not replay.
//
// The memory is a ring: when full, the next experience takes the oldest one's
// place. Samples are keyed by (seed, step, Purpose::Replay), so the same run
// replays the same experiences on every machine and after a restart.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "predictors/predictors.hpp"

namespace afford {

class ExperienceMemory {
 public:
  // Throws std::invalid_argument for a capacity of 0.
  explicit ExperienceMemory(std::size_t capacity);

  void add(Experience e);
  std::size_t size() const { return ring_.size(); }
  std::size_t capacity() const { return capacity_; }
  // The i-th experience held, oldest first.
  const Experience& at(std::size_t i) const;
  // `count` experiences drawn uniformly, with replacement, by the key
  // (seed, step): indices into at(). None from an empty memory.
  std::vector<std::size_t> sample(std::int64_t seed, std::int64_t step, std::size_t count) const;

 private:
  std::size_t capacity_;
  std::vector<Experience> ring_;
  std::size_t oldest_ = 0;  // where the oldest is, once the ring is full
};

}  // namespace afford
