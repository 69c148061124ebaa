#include "experiment/run/silence.hpp"

#include <algorithm>

namespace afford {

void Silence::look(const std::string& run_id, const std::vector<Heard>& heard, Clock::time_point now) {
  if (looked_ == Clock::time_point{} || now - looked_ > after_ / 2) listening_since_ = now;
  looked_ = now;
  std::string waiting;
  for (const Heard& h : heard) {
    const auto it = silent_.find(h.process);
    if (now - std::max(h.at, listening_since_) < after_) {
      if (it != silent_.end()) {
        log_->warn("run '{}': process {} heard again (pid {}), after {:.1f} s", run_id, h.process, h.pid,
                   std::chrono::duration<double>(h.at - it->second).count());
        silent_.erase(it);
      }
      continue;
    }
    waiting += (waiting.empty() ? "" : ", ") + h.process;
    if (it != silent_.end()) continue;  // said already
    silent_[h.process] = h.at;
    log_->warn("run '{}': process {} not heard for {:.1f} s (pid {} last): paused, or restarted elsewhere? check "
               "its bus URL (--lcm-url) and key",
               run_id, h.process, std::chrono::duration<double>(now - h.at).count(), h.pid);
  }
  if (waiting == waiting_) return;
  waiting_ = waiting;
  if (on_waiting_) on_waiting_(waiting_);
}

void Silence::reset() {
  silent_.clear();
  looked_ = {};
  if (waiting_.empty()) return;
  waiting_.clear();
  if (on_waiting_) on_waiting_(waiting_);
}

}  // namespace afford
