// The runner's watch on the processes of a run that go silent. One not heard
// (no STATUS) for a few heartbeats mid-run is said at once, once: killed and
// started again on another bus (a wrong --lcm-url) is never heard again, and
// the run would otherwise only fail when it stalls, half a minute later. The
// progress display is told whom the run waits for, so that it shows that
// rather than a time left that only grows. A process heard again is said back.
// Only a silence the runner listened through counts: after a pause of its own
// (a long handler in its thread), it listens afresh before it says anything.
#pragma once
#include <spdlog/spdlog.h>

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace afford {

class Silence {
 public:
  using Clock = std::chrono::steady_clock;
  // A process of the run as last heard.
  struct Heard {
    std::string process;
    int pid = 0;
    Clock::time_point at;
  };
  // Silent: not heard for `after` (the driver gives a few heartbeats).
  Silence(std::shared_ptr<spdlog::logger> log, Clock::duration after) : log_(std::move(log)), after_(after) {}
  // Told the processes waited for ("eye, planner"), "" once every one is heard again.
  void onWaiting(std::function<void(const std::string&)> f) { on_waiting_ = std::move(f); }
  // The run's processes heard so far, at `now`: each silence is said once, as it begins.
  void look(const std::string& run_id, const std::vector<Heard>& heard, Clock::time_point now);
  // A run ends: nobody is waited for.
  void reset();
  const std::string& waitingFor() const { return waiting_; }

 private:
  std::shared_ptr<spdlog::logger> log_;
  Clock::duration after_;
  std::function<void(const std::string&)> on_waiting_;
  std::map<std::string, Clock::time_point> silent_;  // process -> when it was last heard (silent since)
  std::string waiting_;
  Clock::time_point looked_{}, listening_since_{};  // the last look; the first of the looks since without a pause
};

}  // namespace afford
