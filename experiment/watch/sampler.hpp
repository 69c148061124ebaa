// What afford watch takes of the channels said every step. FOCUS and PREDICTION come once a step, and a
// page shows only the latest of each, a few times a second: the watcher takes them one step at a time, as
// often as a page is sent a state, and lets them go in between (Edge::take: the kernel then drops their
// datagrams). Everything else (SCENE, said on a change; DECISION, whose motivation and threshold make the
// trace; the tables, goals, results) is taken as it comes. Only in the intrinsic phase: the other phases'
// FOCUS also carries the inner eye's scan of a goal (the page's sub-goal), said once a goal.
#pragma once
#include <chrono>
#include <cstdint>
#include <functional>

#include "experiment/watch/state.hpp"

namespace afford {

class StepSampler {
 public:
  using Clock = std::chrono::steady_clock;
  // `take(on)`: take the sampled channels or let them go (afford watch: Edge::take on FOCUS and PREDICTION).
  StepSampler(const WatchState& state, std::function<void(bool)> take, Clock::duration gap);
  // After each turn of the bus: the channels let go once a step's worth is in, taken again `gap` later.
  void tick(Clock::time_point now);
  bool taking() const { return taking_; }

 private:
  void take(bool on);
  const WatchState& state_;
  std::function<void(bool)> take_;
  Clock::duration gap_;
  bool taking_ = true;
  std::int64_t from_ = -1;  // the run's step when the channels were taken again
  Clock::time_point next_{};
};

}  // namespace afford
