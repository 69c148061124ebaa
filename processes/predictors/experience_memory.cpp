#include "predictors/experience_memory.hpp"

#include <stdexcept>
#include <string>
#include <utility>

#include "afford/rng.hpp"

namespace afford {

ExperienceMemory::ExperienceMemory(std::size_t capacity) : capacity_(capacity) {
  if (capacity == 0) throw std::invalid_argument("an experience memory needs a capacity of at least 1");
  ring_.reserve(capacity);
}

void ExperienceMemory::add(Experience e) {
  if (ring_.size() < capacity_) {
    ring_.push_back(std::move(e));
    return;
  }
  ring_[oldest_] = std::move(e);
  oldest_ = (oldest_ + 1) % capacity_;
}

const Experience& ExperienceMemory::at(std::size_t i) const {
  if (i >= ring_.size())
    throw std::out_of_range("experience " + std::to_string(i) + " of a memory holding " + std::to_string(ring_.size()));
  return ring_[(oldest_ + i) % ring_.size()];
}

std::vector<std::size_t> ExperienceMemory::sample(std::int64_t seed, std::int64_t step, std::size_t count) const {
  std::vector<std::size_t> out;
  if (ring_.empty()) return out;
  const KeyedRng rng(seed, step, Purpose::Replay);
  out.reserve(count);
  for (std::size_t k = 0; k < count; ++k)
    out.push_back(static_cast<std::size_t>(rng.uniform(k) * static_cast<double>(ring_.size())));
  return out;
}

}  // namespace afford
