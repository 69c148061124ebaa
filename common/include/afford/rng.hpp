// Keyed random numbers (docs/processes-and-channels.md#determinism): every draw is a pure
// function of (run seed, step, purpose, index), so the same draw is made by
// whoever makes it and however often it is remade, and no generator state has
// to survive a restart. Counter-based: index i of a key is mix(key, i).
#pragma once
#include <cstdint>
#include <string_view>

namespace afford {

// What a draw is for. Values are part of the reproducibility contract: never
// renumber, only append.
enum class Purpose : std::uint64_t {
  ScanNoise = 1,          // eye: saliency noise of a scan (index = attempt * pixels + pixel)
  EffectNoise = 2,        // eye: saliency noise of the change-driven scan
  MoveTarget = 3,         // environment: random free target of the intrinsic move
  ActionSuccess = 4,      // environment: stochastic success of an action
  LearningProgressInit = 5, // predictors: initial learning-progress weights
  LatePlacement = 6,      // environment: free place for a late object whose spot is taken
  GoalScanNoise = 7,      // eye: saliency noise of the inner eye's scan of the goal image
  RandomTable = 8,        // experiments: the entries of a random affordance table (index = table)
  Replay = 9,             // predictors: which remembered experiences are replayed at a step
  Revisit = 10,           // motivation: the order of never-tried colour changes (revisit.order: random)
  ScenarioGeneration = 11,  // experiments: a generated scenario (step = its index, sub-key = the attempt)
  Component = 12,         // a component of one's own (docs/writing-a-component.md): sub-key = its own constant
  GoalChoice = 13,        // motivation, goals phase: the module, the goal in it, an exploration (sub-key = goal id)
  PrimitiveNoise = 14,    // environment, the table world: a motor primitive's noise (sub-key = the action)
  TableTruth = 15,        // the table world's truth: a trial's pose and place (step = object x actions + action)
  TableScene = 16,        // environment, the table world: the scene's set-up (the objects' places and turns)
  TablePlace = 17,        // environment, the table world: the place of an intrinsic push or carry
};

constexpr std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

class KeyedRng {
 public:
  KeyedRng(std::int64_t seed, std::int64_t step, Purpose purpose, std::uint64_t sub = 0)
      : key_(splitmix64(splitmix64(splitmix64(splitmix64(static_cast<std::uint64_t>(seed)) ^
                                              static_cast<std::uint64_t>(step)) ^
                                   static_cast<std::uint64_t>(purpose)) ^
                        sub)) {}

  // The i-th 64-bit draw of this key.
  std::uint64_t bits(std::uint64_t i) const { return splitmix64(key_ ^ splitmix64(i + 1)); }
  // Uniform in [0, 1).
  double uniform(std::uint64_t i) const { return static_cast<double>(bits(i) >> 11) * 0x1.0p-53; }
  // Uniform in [lo, hi).
  double uniform(std::uint64_t i, double lo, double hi) const { return lo + (hi - lo) * uniform(i); }

 private:
  std::uint64_t key_;
};

}  // namespace afford
