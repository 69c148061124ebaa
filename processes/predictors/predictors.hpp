// Predictors core (paper 2.3.3): for each of the 4 actions, an affordance
// perceptron (sigmoid), a learning-progress perceptron (linear), a what-effect
// perceptron (1323 sigmoid outputs) and a where-effect perceptron (2 linear
// outputs), trained as Algorithm 1 lines 7-12 say. No LCM here.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "afford/actions.hpp"
#include "afford/config.hpp"
#include "afford/perceptron.hpp"

namespace afford {

using PerAction = std::array<double, kNumActions>;

struct Prediction {
  PerAction affordance{};
  PerAction learning_progress{};
};

// One executed action, as the eye reported it.
struct Experience {
  int action = 0;
  std::vector<std::uint8_t> before_image;  // focus image of the scan (object_image)
  double before_x = 0, before_y = 0;       // object_position
  double target_x = -1, target_y = -1;     // move target (where-effect input)
  bool affordance = false;                 // the action's effect was seen
  std::vector<std::uint8_t> after_image;   // new_object_image
  double after_x = 0, after_y = 0;         // new_object_position
};

struct TrainingReport {
  int action = 0;
  bool affordance = false;
  double affordance_before = 0, affordance_after = 0;
  double learning_progress = 0;            // LP output before its update
  bool effect_trained = false;
};

class Predictors {
 public:
  explicit Predictors(const RunConfig& config);

  Prediction predict(const std::vector<std::uint8_t>& focus_image) const;
  // Algorithm 1 lines 7-12: trainAffordance() then trainEffects().
  TrainingReport train(const Experience& e);
  // Lines 7-9: the affordance predictor, and the learning-progress predictor (IMP).
  TrainingReport trainAffordance(const Experience& e);
  // Lines 10-12: what- and where-effect predictors, if the action succeeded.
  // Nothing in the intrinsic phase reads them, so the node may run this after
  // publishing the next prediction; each model still sees the same updates in
  // the same order.
  void trainEffects(const Experience& e);
  // Affordance outputs for each probe image (rows) and action (columns).
  std::vector<PerAction> table(const std::vector<std::vector<std::uint8_t>>& probes) const;
  // Forward models (used by the planner in the extrinsic phase).
  std::vector<double> whatEffect(int action, const std::vector<std::uint8_t>& focus_image) const;
  std::array<double, 2> whereEffect(int action, double x, double y, double target_x, double target_y) const;

  // FNV-1a 64 of every weight, in a fixed order (hex).
  std::string weightsChecksum() const;

  // Checkpoint: every weight and counter, in the checksum's order, in a binary
  // file that ends with the checksum. save() writes atomically (temp + rename);
  // load() throws std::runtime_error naming the file and the problem (missing,
  // wrong format, other dimensions, checksum mismatch).
  void save(const std::string& path) const;
  void load(const std::string& path);
  const std::array<std::int64_t, kNumActions>& executed() const { return executed_; }
  const std::array<std::int64_t, kNumActions>& successes() const { return successes_; }

 private:
  SparseInput whereInput(int action, double x, double y, double tx, double ty) const;

  RunConfig config_;
  int input_size_;
  std::vector<Unit> affordance_, learning_progress_;
  std::vector<Layer> what_, where_;
  std::array<std::int64_t, kNumActions> executed_{}, successes_{};
};

}  // namespace afford
