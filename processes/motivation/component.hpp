// What a motivation is, for someone who writes one (docs/writing-a-component.md):
// the motivation process's node takes each step's PREDICTION by its input rule
// (in step order, once) and gives the component what the predictors say of the
// focused object; the component says whether to act, and with which action;
// the node publishes the DECISION. A component holds no protocol code.
//
// For exact replay and live restart, a component's state must be a pure
// function of the percepts it was given, in order, and of the run's
// configuration; randomness comes from KeyedRng(config.seed, step, purpose)
// (afford/rng.hpp), never from a clock or a global generator.
//
// The motivation.kind config key picks the component: `paper` (FIX, IGN and
// IMP, the system of the run: paper 2.4.1) and `novelty` ship; a process of
// one's own registers more (registerMotivation) before it starts.
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "afford/actions.hpp"
#include "afford/config.hpp"
#include "afford/snapshot.hpp"
#include "motivation/motivation.hpp"

namespace afford {

// What the predictors say of the object in focus at `step` (one PREDICTION).
struct Percept {
  std::int64_t step = 0;
  std::array<double, kNumActions> affordance{};          // predicted success of each action
  std::array<double, kNumActions> learning_progress{};   // predicted change of each affordance output
  // With the predictors' memory (RunConfig::keepsMemory): which look the focus
  // is (the same object seen again), and the steps since each action was last
  // tried on it (-1: never).
  int look = -1;
  std::optional<std::array<std::int64_t, kNumActions>> tried_ago;
  // |change| of the affordance output that the previous step's action caused
  // (its update report), when there is one.
  std::optional<double> last_change;
};

class MotivationComponent {
 public:
  virtual ~MotivationComponent() = default;
  // Act (and with which action) or pass, for this step's percept.
  virtual Decision decide(const Percept& p) = 0;
  // Must this step's percept carry the previous step's update report? (The
  // node then waits for, or refuses, a PREDICTION without it.)
  virtual bool needsLastChange() const { return false; }
  // Must the percepts say which look the focus is and what was tried on it
  // (the predictors' memory, which they keep for every kind but paper)?
  virtual bool needsMemory() const { return false; }
  // Snapshots (docs/processes-and-channels.md, "Runs of any length"): a
  // component that saves its state (what decide() changes) says so and writes
  // it, then reads it back in the same order. One that does not is restarted
  // from the run's start: its peers hold what they published for it, up to
  // protocol.recovery.history_mb.
  virtual bool snapshots() const { return false; }
  virtual void save(SnapshotWriter&) const {}
  virtual void load(SnapshotReader&) {}
};

using MotivationFactory = std::function<std::unique_ptr<MotivationComponent>(const MotivationParams&)>;
// Make `kind` available to motivation.kind (a process of one's own does this before processMain).
void registerMotivation(const std::string& kind, MotivationFactory factory);

// Deprecated: a factory of the whole RunConfig (the form of the docs before MotivationParams). It still
// registers: it is given the run's configuration parsed from MotivationParams::config_text, and says once, when
// registered, what to write instead. To be removed in the release after 0.2.0 (docs/releases.md).
using RunConfigMotivationFactory = std::function<std::unique_ptr<MotivationComponent>(const RunConfig&)>;
void registerRunConfigMotivation(const std::string& kind, RunConfigMotivationFactory factory);
template <class F, std::enable_if_t<std::is_invocable_v<const F&, const RunConfig&> &&
                                        !std::is_invocable_v<const F&, const MotivationParams&>,
                                    int> = 0>
[[deprecated("a motivation's factory takes const afford::MotivationParams& (its section, system, seed, steps and "
             "config_text); the RunConfig form is kept for 0.2.0 only")]] void
registerMotivation(const std::string& kind, F factory) {
  registerRunConfigMotivation(kind, RunConfigMotivationFactory(std::move(factory)));
}
// The kinds registered, the shipped ones first.
std::vector<std::string> motivationKinds();
// The component motivation.kind names; throws ConfigError naming the key and the kinds known.
std::unique_ptr<MotivationComponent> makeMotivation(const MotivationParams& params);
// The shipped novelty motivation (motivation/novelty.cpp).
std::unique_ptr<MotivationComponent> makeNoveltyMotivation(const MotivationParams& params);

}  // namespace afford
