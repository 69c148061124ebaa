// The phases of a run: what the agent does in it, and so which processes take
// part and who publishes each channel (afford/protocol.hpp, afford/processes.hpp).
#pragma once
#include <cstddef>

namespace afford {

enum class Phase {
  Intrinsic,  // learning: the motivation decides each step (paper Algorithm 1)
  Extrinsic,  // a test: the planner pursues a given goal with a trained agent (Algorithms 2 and 3)
  Goals,      // learning: the agent sets its own goals and the planner pursues them (docs/model.md#goals-of-its-own)
};
inline constexpr std::size_t kPhases = 3;

// A phase in which the agent learns (curves, a checkpoint, snapshots).
constexpr bool learning(Phase p) { return p != Phase::Extrinsic; }

}  // namespace afford
