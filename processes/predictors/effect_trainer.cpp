#include "predictors/effect_trainer.hpp"

namespace afford {

EffectTrainer::EffectTrainer(Predictors& core) : core_(core), thread_([this] { work(); }) {}

EffectTrainer::~EffectTrainer() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  thread_.join();
}

void EffectTrainer::push(std::vector<Memory::Ref> updates) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    queue_.push_back(std::move(updates));
  }
  changed_.notify_all();
}

void EffectTrainer::drain() {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [this] { return queue_.empty() && !busy_; });
}

void EffectTrainer::work() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    changed_.wait(lock, [this] { return stop_ || !queue_.empty(); });
    if (queue_.empty()) return;  // stopping, nothing left
    std::vector<Memory::Ref> updates = std::move(queue_.front());
    queue_.pop_front();
    busy_ = true;
    lock.unlock();
    core_.trainEffects(updates);
    lock.lock();
    busy_ = false;
    changed_.notify_all();
  }
}

}  // namespace afford
