// What an affordance predictor is, for someone who writes one
// (docs/writing-a-component.md#the-affordance-predictor): the part of the
// predictors that says, for the focused object, how likely each action is to
// have its effect (the affordance) and how much that belief is changing (the
// learning progress, IMP's signal), and learns both from each executed action
// (paper 2.3.3, Algorithm 1 lines 7-9). The predictors core around it keeps
// the forward models, the memory and replay, and the node the protocol: a
// component holds neither.
//
// For exact replay, live restart and checkpoints, a component's whole state is
// arrays of doubles (state()): the weights checksum hashes them, a checkpoint
// saves them, and loading one writes into them. The state must be a pure
// function of the calls made, in order, and of the run's configuration;
// randomness comes from KeyedRng(config.seed, step, purpose) (afford/rng.hpp).
//
// The predictors.affordance.kind config key picks the component: `paper`
// ships; a process of one's own registers more (registerAffordance) before it
// starts.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "afford/actions.hpp"
#include "afford/config.hpp"
#include "predictors/perceptron.hpp"

namespace afford {

using PerAction = std::array<double, kNumActions>;

// A focus image as a component gets it: the bytes (side x side x 3, RGB) and
// the same as the paper's perceptrons take them (focusInput: value / 255, then
// a bias of 1, zeros left out).
struct FocusView {
  const std::vector<std::uint8_t>& image;
  const SparseInput& input;
};

// What learning from one executed action reports (TRAINED on the bus).
struct Learned {
  double before = 0;             // the action's affordance output before the update
  double after = 0;              // ... and after it
  double learning_progress = 0;  // the action's learning-progress output before its own update
};

// One array of a component's state: `size` doubles at `data`, which stay valid
// until the component's next call.
struct StateArray {
  double* data = nullptr;
  std::size_t size = 0;
};

class AffordanceComponent {
 public:
  virtual ~AffordanceComponent() = default;
  // The affordance (predicted success, 0..1) and the learning progress of each action on this focus.
  virtual void predict(const FocusView& focus, PerAction& affordance, PerAction& learning_progress) const = 0;
  // Learn from `action` executed on `focus`, which had its effect (`succeeded`) or not.
  virtual Learned learn(const FocusView& focus, int action, bool succeeded) = 0;
  // Replay (docs/model.md#replay): learn the affordance again from a remembered experience; no learning progress.
  virtual void relearn(const FocusView& focus, int action, bool succeeded) = 0;
  // The state that goes with `action`, in a fixed order: the weights checksum
  // and checkpoints take the arrays of action 0, then the forward models of
  // action 0, then those of action 1, and so on. A component may give all of
  // its state with action 0 and none with the others.
  virtual std::vector<StateArray> state(int action) = 0;
};

// What an affordance predictor is given of the run's configuration: the predictors' section, the focus
// image's side, the run's system and seed; and for a component written in another language (Python), the
// whole configuration as its RUN_CONFIG carries it.
struct AffordanceParams {
  PredictorsConfig predictors;
  int focus_side = 0;
  System system = System::IMP;
  std::int64_t seed = 0;
  std::int64_t steps = 0;
  std::string experiment;
  std::string motivation_kind;
  std::string config_text;  // the run's configuration, YAML (for a component that reads it whole)
  AffordanceParams() = default;
  AffordanceParams(const RunConfig& c)  // NOLINT: the section a run's configuration gives
      : predictors(c.predictors), focus_side(c.eye.focus_side), system(c.system), seed(c.seed), steps(c.steps),
        experiment(c.experiment), motivation_kind(c.motivation.kind), config_text(c.text) {}
};

using AffordanceFactory = std::function<std::unique_ptr<AffordanceComponent>(const AffordanceParams&)>;
// Make `kind` available to predictors.affordance.kind (a process of one's own does this before processMain).
void registerAffordance(const std::string& kind, AffordanceFactory factory);
// The kinds registered, the shipped ones first.
std::vector<std::string> affordanceKinds();
// The component predictors.affordance.kind names; throws ConfigError naming the key and the kinds known.
std::unique_ptr<AffordanceComponent> makeAffordance(const AffordanceParams& params);

}  // namespace afford
