// Predictors process node. Takes each step's inputs in the canonical order
// PROBE, then FOCUS(t) -> DECISION(t) -> [EFFECT(t)] -> FOCUS(t+1), by the
// input rules stated in its constructor (NodeBase::takes), so its state is a
// pure function of the run's messages.
// Channels in:  RUN_CONFIG, RUN_CONTROL, PROBE, FOCUS, DECISION, EFFECT,
//               FORWARD_QUERY (extrinsic phase)
// Channels out: AFFORDANCE_TABLE (every run.curve_interval steps and at the end),
//               PREDICTION (with the report of the last update, if any, and with a
//               memory, what was tried on the focused look), RESULT,
//               FORWARD_PREDICTION (extrinsic phase), STATUS
// Extrinsic phase: the predictors load the checkpoint of a trained agent,
// predict affordances for each scene scan and answer forward queries; they do
// not learn. Checkpoints are written and read only inside the process's
// checkpoint folder (--checkpoint-dir, default logs/), a run's own in
// <root>/<run-id>/.
#pragma once
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <set>

#include "afford/decision_t.hpp"
#include "afford/effect_t.hpp"
#include "afford/focus_t.hpp"
#include "afford/forward_query_t.hpp"
#include "afford/node.hpp"
#include "afford/object_probe_t.hpp"
#include "afford/trained_t.hpp"
#include "predictors/effect_trainer.hpp"
#include "predictors/predictors.hpp"

namespace afford {

class PredictorsNode : public NodeBase {
 public:
  // `async_effects`: make the forward-model updates on a worker thread
  // (EffectTrainer) instead of inline after the next prediction. Same results;
  // it pays where a second core is free, not in a single-threaded memq host.
  // `checkpoint_root`: the only folder the predictors write checkpoints in (as
  // <root>/<run-id>/NAME.ckpt) and load them from (--checkpoint-dir): a run's
  // configuration names the file, but a path elsewhere is refused.
  PredictorsNode(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol,
                 bool async_effects = true, std::string checkpoint_root = "logs");

 private:
  enum class Outcome { Unknown, Passed, AwaitingEffect, Learned };

  void onConfigured(const RunConfig& config) override;
  void onStop() override;
  bool snapshots() const override { return true; }
  void prepareSnapshot() override;
  void saveState(SnapshotWriter& w) override;
  void loadState(SnapshotReader& r) override;
  void decided(const decision_t& m);         // intrinsic: the decision of the current step
  void learn(const effect_t& m);             // intrinsic: its effect, learned from
  void takeQueries();  // the FORWARD_QUERY input of each phase (the constructor states the others)
  void answer(const forward_query_t& q);     // extrinsic: what actions would do
  Prediction publishPrediction(const focus_t& m);  // what it published
  bool extrinsic() const { return config().phase == Phase::Extrinsic; }
  void handleFocus(const focus_t& m);
  void publishTable(std::int64_t step);
  // run.checkpoint_after_actions: save the weights once that many actions are learned.
  void saveActionsCheckpoint();
  void finish();
  void trainPendingEffects();

  // Is the run's checkpoint (to write, or to load) where this process may use one? Throws ConfigError if not.
  void checkCheckpointPath(const RunConfig& config) const;

  bool async_effects_;
  std::string checkpoint_root_;
  std::shared_ptr<Predictors> core_;
  // Extrinsic runs do not change the predictors: the agent loaded for one test
  // serves the next one that names the same, unchanged checkpoint file.
  struct Loaded {
    std::string path;
    std::uintmax_t size = 0;
    std::filesystem::file_time_type mtime;
    std::shared_ptr<Predictors> core;
    // The what-effect predictions already made with these weights, by action
    // and focus image: a planner asks the same ones step after step, test after
    // test. Bounded: emptied when it reaches kWhatKept.
    std::map<std::pair<int, std::vector<std::uint8_t>>, std::vector<double>> what;
  };
  static constexpr std::size_t kWhatKept = 2048;  // of 1323 doubles each: at most ~22 MB
  std::optional<Loaded> loaded_;
  // The checkpoints this process saved, and the request (its RUN_CONFIG's digest) each was saved for.
  std::map<std::string, std::int64_t> saved_;
  std::unique_ptr<EffectTrainer> trainer_;  // declared after core_: stops before it goes
  std::vector<std::vector<std::uint8_t>> probes_;
  std::int64_t current_ = -1;          // the step whose focus was handled last
  Outcome outcome_ = Outcome::Unknown; // of step current_
  int action_ = -1;                    // executed at step current_
  focus_t focus_;                      // of step current_
  int look_ = -1;                      // with a memory: the look of step current_'s focus
  std::optional<trained_t> pending_trained_;
  std::vector<Memory::Ref> pending_effects_;  // forward-model updates still to make
  std::int64_t revisits_ = 0;          // executed actions the motivation's revisit rule chose
  bool finished_ = false;
  std::int32_t last_query_ = -1;  // extrinsic: last FORWARD_QUERY answered
  // Goals phase: the planner's requests (LOOK and FORWARD_QUERY share one seq, from 1) seen answered (a
  // FOCUS, or an answer of ours). A process catching up takes a message only after every request before it,
  // in the order the run had: a query of step t before the decision of step t.
  class Requests {
   public:
    void answered(std::int32_t seq) {
      if (seq > done_ && ahead_.size() < kMostAhead) ahead_.insert(seq);
      while (ahead_.erase(done_ + 1)) ++done_;
    }
    bool before(std::int64_t seq) const { return done_ >= seq - 1; }  // every request below seq answered
    void clear() {
      done_ = 0;
      ahead_.clear();
    }
    void save(SnapshotWriter& w) const;
    void load(SnapshotReader& r);

   private:
    static constexpr std::size_t kMostAhead = 4096;  // (requests come one at a time: a few at most)
    std::int32_t done_ = 0;
    std::set<std::int32_t> ahead_;
  } requests_;
};

}  // namespace afford
