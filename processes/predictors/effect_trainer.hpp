// Applies forward-model (what- and where-effect) updates on a worker thread,
// one at a time in the order they were queued, so they overlap with the next
// steps of the choreography. The affordance path never touches those models,
// and drain() is called before anything reads them (weights checksum,
// forward-model queries), so results are bit-identical to updating inline.
// In the goals phase it also computes ahead, after the updates queued before,
// the what-effect outputs a query is expected to ask for (Predictors keeps
// each model's last output): the query then finds them made. Each what-effect
// output and update is split by rows with a second thread (SecondCore): the
// same values, in about half the time where a second core is free.
#pragma once
#include <condition_variable>
#include <deque>
#include <mutex>
#include <thread>

#include "predictors/predictors.hpp"

namespace afford {

class EffectTrainer {
 public:
  explicit EffectTrainer(Predictors& core);
  ~EffectTrainer();
  EffectTrainer(const EffectTrainer&) = delete;
  EffectTrainer& operator=(const EffectTrainer&) = delete;

  // The forward-model updates of one executed action (TrainingReport::effect_updates).
  void push(std::vector<Memory::Ref> updates);
  // The what-effect outputs of `actions` for `image`, once the updates queued before are made.
  void ahead(std::vector<int> actions, std::vector<std::uint8_t> image);
  // Block until every queued update is applied.
  void drain();

 private:
  struct Job {
    std::vector<Memory::Ref> updates;
    std::vector<int> actions;  // ahead(): the outputs to make for `image`
    std::vector<std::uint8_t> image;
  };
  void add(Job job);
  void work();

  Predictors& core_;
  SecondCore second_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<Job> queue_;
  bool busy_ = false, stop_ = false;
  std::thread thread_;
};

}  // namespace afford
