#include "predictors/effect_trainer.hpp"

namespace afford {

EffectTrainer::EffectTrainer(Predictors& core) : core_(core), thread_([this] { work(); }) {
  core_.useSecondCore(&second_);
}

EffectTrainer::~EffectTrainer() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  thread_.join();
  core_.useSecondCore(nullptr);
}

void EffectTrainer::push(std::vector<Memory::Ref> updates) { add(Job{std::move(updates), {}, {}}); }

void EffectTrainer::ahead(std::vector<int> actions, std::vector<std::uint8_t> image) {
  add(Job{{}, std::move(actions), std::move(image)});
}

void EffectTrainer::add(Job job) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    queue_.push_back(std::move(job));
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
    Job job = std::move(queue_.front());
    queue_.pop_front();
    busy_ = true;
    lock.unlock();
    core_.trainEffects(job.updates);
    for (int a : job.actions) (void)core_.whatEffect(a, job.image);
    lock.lock();
    busy_ = false;
    changed_.notify_all();
  }
}

}  // namespace afford
