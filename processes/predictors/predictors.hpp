// Predictors core (paper 2.3.3): the affordance component (affordance.hpp: by
// default, for each of the 4 actions an affordance perceptron, sigmoid, and a
// learning-progress perceptron, linear), and for each action a what-effect
// perceptron (1323 sigmoid outputs) and a where-effect perceptron (2 linear
// outputs), trained as Algorithm 1 lines 7-12 say. No LCM here.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <memory>

#include "afford/actions.hpp"
#include "afford/config.hpp"
#include "predictors/perceptron.hpp"
#include "predictors/affordance.hpp"
#include "predictors/experience.hpp"
#include "predictors/memory.hpp"

namespace afford {

class SnapshotWriter;
class SnapshotReader;

struct Prediction {
  PerAction affordance{};
  PerAction learning_progress{};
  // With a memory (see()): the focused look, and the steps since each action
  // was last tried on it (-1: never).
  bool remembered = false;
  int look = -1;
  Memory::TriedAgo tried_ago{-1, -1, -1, -1};
};


struct TrainingReport {
  int action = 0;
  bool affordance = false;
  double affordance_before = 0, affordance_after = 0;
  double learning_progress = 0;            // LP output before its update
  bool effect_trained = false;
  // The forward-model updates this action calls for, in order: its own if its
  // effect was seen, then the replayed ones (trainEffects).
  std::vector<Memory::Ref> effect_updates;
};

// What the predictors are given of the run's configuration: their affordance component's (their section,
// the focus image's side, the run's system and seed), and whether they keep a memory (RunConfig::keepsMemory,
// which the motivation's section decides too), and the world (which actions are given a place).
struct PredictorsParams {
  AffordanceParams component;
  bool keeps_memory = false;
  WorldKind world = WorldKind::Grid;
  PredictorsParams() = default;
  PredictorsParams(const RunConfig& c)  // NOLINT: its sections
      : component(c), keeps_memory(c.keepsMemory()), world(c.world.kind) {}
};

class Predictors {
 public:
  explicit Predictors(const PredictorsParams& params);

  Prediction predict(const std::vector<std::uint8_t>& focus_image) const;
  // The intrinsic phase's prediction for the focus of `step`: predict(), and
  // with a memory, the look it shows (remembered from now on) and what was
  // tried on it.
  Prediction see(const std::vector<std::uint8_t>& focus_image, std::int64_t step);
  // Algorithm 1 lines 7-12: trainAffordance() then trainEffects().
  TrainingReport train(const Experience& e, std::int64_t step = 0, int look = -1);
  // Lines 7-9: the affordance predictor, and the learning-progress predictor
  // (IMP). With a memory, the experience is filed under `look` (what see()
  // returned for its focus at `step`; required), then the step's replay().
  TrainingReport trainAffordance(const Experience& e, std::int64_t step = 0, int look = -1);
  // With predictors.replay, the replay of `step` (every step: after the
  // step's own update, or after a pass): predictors.replay.ratio remembered
  // experiences, drawn by (seed, step), each one update of its affordance
  // predictor; returns the forward-model updates, drawn from experiences whose
  // effect was seen, that make up effects_ratio with the step's own
  // (`own_effect`: the step's action had its effect), for trainEffects.
  // Nothing without replay.
  std::vector<Memory::Ref> replay(std::int64_t step, bool own_effect = false);
  // Lines 10-12: what- and where-effect predictors, from a report's
  // effect_updates. Nothing in the intrinsic phase reads them, so the node
  // may run this after publishing the next prediction, or on another thread;
  // each model still sees the same updates in the same order. Touches the
  // forward models only.
  void trainEffects(const std::vector<Memory::Ref>& updates);
  // One update of the forward models, if the experience's effect was seen.
  void trainEffects(const Experience& e);
  // Affordance outputs for each probe image (rows) and action (columns).
  std::vector<PerAction> table(const std::vector<std::vector<std::uint8_t>>& probes) const;
  // Forward models (used by the planner in the extrinsic phase).
  std::vector<double> whatEffect(int action, const std::vector<std::uint8_t>& focus_image) const;
  std::array<double, 2> whereEffect(int action, double x, double y, double target_x, double target_y) const;

  // FNV-1a 64 of every weight, in a fixed order (per action: the affordance
  // component's state, then the forward models), then of the memory if there
  // is one (hex): the predictors' whole state. Without a memory, the weights'
  // checksum of the paper's agent.
  std::string weightsChecksum() const;

  // Checkpoint: every weight and counter, in the checksum's order, then the
  // checksum, deflated by zlib (lossless: the same weights come back, and the
  // same decisions; checkpoints written plain before still load). save() writes atomically (temp + rename);
  // load() throws std::runtime_error naming the file and the problem (missing,
  // wrong format, other dimensions, another affordance component, checksum
  // mismatch). The file names its affordance component and the release that wrote it (format 4, 0.2.0 on).
  // `checksum`: weightsChecksum() if the caller has it already (it takes a
  // pass over every weight), "" to compute it.
  void save(const std::string& path, const std::string& checksum = "") const;
  void load(const std::string& path);
  // A snapshot's part (afford/snapshot.hpp): the checkpoint's plain content, as save() deflates it.
  void save(SnapshotWriter& w) const;
  void load(SnapshotReader& r);
  // The bytes of the forward models' weights for focus images of `focus_side`, without building them: most
  // of a snapshot's or a plain checkpoint's content (the affordance component and the memory are small).
  static std::uint64_t forwardModelBytes(int focus_side, WorldKind world);
  const std::array<std::int64_t, kNumActions>& executed() const { return executed_; }
  const std::array<std::int64_t, kNumActions>& successes() const { return successes_; }
  // The memory, if the configuration keeps one (RunConfig::keepsMemory).
  const Memory* memory() const { return memory_.get(); }
  std::int64_t replayedUpdates() const { return replayed_; }         // affordance updates replayed
  std::int64_t replayedEffectUpdates() const { return replayed_effects_; }  // forward-model updates replayed
  // What-effect outputs computed (for a query or an update), not taken from the model's last output.
  std::int64_t whatOutputs() const { return what_outputs_; }
  // Split the what-effect models' outputs and updates with `second` (not owned; nullptr: none). The values
  // are the same; the caller makes sure no two threads use the models at once.
  void useSecondCore(SecondCore* second) { second_ = second; }
  // The release that wrote the checkpoint last loaded ("0.1.0 or earlier" before format 4); "" if none was.
  const std::string& checkpointWrittenBy() const { return written_by_; }

 private:
  SparseInput whereInput(int action, double x, double y, double tx, double ty) const;
  void loadFrom(std::istream& in, const std::string& path);  // the plain format, from its magic on
  // The plain format to `out` (write(const void*, size_t)): `memory`, the memory's saved bytes.
  template <class Out>
  void writePlain(Out& out, const std::string& checksum, const std::string& memory) const;
  // f(data, size) for every array of the state, in the checksum's order.
  template <class F>
  void forEachWeightArray(F&& f) const;

  PredictorsConfig config_;
  int focus_side_;
  std::int64_t seed_;
  WorldKind world_ = WorldKind::Grid;
  int input_size_;
  std::unique_ptr<AffordanceComponent> affordance_;
  std::vector<Layer> what_, where_;
  // Each what-effect model's last output and the image it was for, until that model learns or weights are
  // loaded: a query asked again of an unchanged model is answered from it, and the update after an action the
  // planner asked about starts from it (goals phase). The values are those the model would compute again.
  struct LastOutput {
    bool valid = false;
    std::vector<std::uint8_t> image;
    Eigen::VectorXd y;
  };
  mutable std::array<LastOutput, kNumActions> last_what_;
  mutable std::int64_t what_outputs_ = 0;
  SecondCore* second_ = nullptr;
  std::array<std::int64_t, kNumActions> executed_{}, successes_{};
  std::string written_by_;
  std::unique_ptr<Memory> memory_;
  std::int64_t replayed_ = 0, replayed_effects_ = 0;
};

}  // namespace afford
