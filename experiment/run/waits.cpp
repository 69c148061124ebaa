// The runner's waits (RunDriver's stages, experiment/run/driver.hpp): every
// process free, every one configured, the run's steps and its result, the
// logger's log whole, and, after STOP, the log closed. Each wait's deadline
// counts from the last progress of what it waits for, never from the wait's
// start: a process that is slow but moving is waited for (a logger catching
// up after a restart or a pause included); timers only recover losses.
#include <algorithm>

#include "afford/process_main.hpp"
#include "afford/process_status_t.hpp"
#include "afford/processes.hpp"
#include "afford/protocol.hpp"
#include "afford/run_control_t.hpp"
#include "experiment/run/driver.hpp"

namespace afford {

using std::chrono::milliseconds;

namespace {
// A wait's progress: its deadline counts from the last time the wait's mark grew.
struct Progress {
  std::int64_t most;
  std::chrono::steady_clock::time_point at = std::chrono::steady_clock::now();
  // Has the mark not grown for longer than `patience`?
  bool stalled(std::int64_t mark, std::chrono::steady_clock::duration patience) {
    const auto now = std::chrono::steady_clock::now();
    if (mark > most) {
      most = mark;
      at = now;
    }
    return now - at > patience;
  }
};
}  // namespace

// 1. Every process present and free (one still in another run is told to stop on its next STATUS).
RunDriver::Ending RunDriver::waitFree(const Waiting& w) {
  const ProtocolConfig& protocol = config_.protocol;
  const auto fresh = milliseconds(3 * protocol.heartbeat_ms);  // heard within three heartbeats: alive
  const auto free = [&](const Seen& s) {
    return s.state == process_status_t::WAITING && s.run_id.empty() && Clock::now() - s.at < fresh;
  };
  phase_ = Phase::Freeing;
  phase_at_ = Clock::now();
  // The deadline counts from the last progress: one more free, or one still in another run going further (told
  // to stop, a logger catching up closes its log first); one silent for a while (killed, paused) is waited for.
  Progress progress{progressOf(free)};
  const KeyMismatches heard = edge_.drops().key;  // a key that does not fit the bus: why nobody is heard
  while (!missing(free).empty()) {
    if (auto h = w.health(); !h.empty()) return {false, h};
    if (stopRequested()) return {true, ""};
    if (progress.stalled(progressOf(free), milliseconds(protocol.ready_timeout_ms)) && !awaitingSilent(free)) {
      outcome_->unreached = true;  // nothing was said to them yet: the run never began
      const std::string key = edge_.drops().key.since(heard).said();
      return {false, "no process of this name reported free for a run within " +
                         std::to_string(protocol.ready_timeout_ms / 1000.0).substr(0, 4) + " s: " + missing(free) +
                         (key.empty() ? "" : "; " + key)};
    }
    w.pump();
  }
  return {};
}

// 2. Configure: START as soon as every one says READY.
RunDriver::Ending RunDriver::configure(const Waiting& w) {
  const ProtocolConfig& protocol = config_.protocol;
  phase_ = Phase::Configuring;
  edge_.send(ch::runConfig, config_msg_);
  auto said = Clock::now();
  auto again = milliseconds(protocol.retry_ms);
  const auto ready = [&](const Seen& s) { return ourRequest(s) && s.state == process_status_t::READY; };
  Progress progress{progressOf(ready)};  // the deadline counts from the last one that said READY
  while (!missing(ready).empty()) {
    if (auto h = w.health(); !h.empty()) return {false, h};
    if (auto f = failedProcess(); !f.empty()) return {false, f};
    if (stopRequested()) return {true, ""};
    if (progress.stalled(progressOf(ready), milliseconds(protocol.ready_timeout_ms)) && !awaitingSilent(ready))
      return {false, "not configured within the protocol's ready_timeout_ms: " + missing(ready) + foreign()};
    if (Clock::now() - said > again) {  // a datagram lost on the way there or back: say it again, backing off
      edge_.send(ch::runConfig, config_msg_);
      said = Clock::now();
      again = std::min(again * 2, milliseconds(protocol.heartbeat_ms));
    }
    w.pump();
  }
  return {};
}

// 3. Run: until the result and every affordance table are in, and the logger's log holds all that was published.
RunDriver::Ending RunDriver::runSteps(const Waiting& w) {
  const RunSpec& spec = *spec_;
  RunOutcome& out = *outcome_;
  phase_ = Phase::Running;
  sendOurs(run_control_t::START);
  const auto started = Clock::now();
  std::int64_t progress = -1;
  auto progress_at = Clock::now();
  const auto silence = std::chrono::duration<double>(spec.stall_seconds);
  // An intrinsic run reports its affordance table every curve_interval steps and at the end.
  const std::size_t tables = spec.extrinsic ? 0
                                            : static_cast<std::size_t>(config_.steps / config_.curve_interval + 1 +
                                                                       (config_.steps % config_.curve_interval != 0));
  // The run is stopped only once the logger's log holds all that was published: a logger killed, or paused,
  // and started again (continued) after the last step still catches up from its peers, which hold what it
  // lacks while they are in the run.
  // A goals run ends with its last GOAL_RESULT too: the goals' figures are whole.
  const bool goals = config_.phase == afford::Phase::Goals;
  const auto resultIn = [&] { return have_result_ && out.curve.size() >= tables && (!goals || goals_ended_); };
  while (!resultIn() || (logged() && !loggerHolds())) {
    if (resultIn() && out.run_seconds == 0) out.run_seconds = std::chrono::duration<double>(Clock::now() - started).count();
    if (auto h = w.health(); !h.empty()) return {false, h};
    if (auto f = failedProcess(); !f.empty()) return {false, f};
    if (stopRequested()) return {true, ""};
    w.pump();
    edge_.askMissing();
    const auto now = Clock::now();
    std::int64_t handled = 0;  // the steps of all, in the run
    std::vector<Silence::Heard> heard;
    for (const auto& p : spec.processes) {
      auto it = seen_.find(p);
      if (it == seen_.end()) continue;
      heard.push_back({p, it->second.pid, it->second.at});
      if (now - it->second.at > silence)
        return {false, "process '" + p + "' stopped reporting (last heard " +
                           std::to_string(std::chrono::duration<double>(now - it->second.at).count()) + " s ago)"};
      if (ourRequest(it->second)) handled += it->second.step + 1 + it->second.taken;
    }
    silence_.look(spec.run_id, heard, now);
    // Progress is any process moving on (a restarted one catching up included: the logger's log growing), or a
    // table coming in.
    if (const auto p = handled + static_cast<std::int64_t>(out.curve.size()); p != progress) {
      progress = p;
      progress_at = now;
    }
    if (now - progress_at > silence) {
      std::string where;
      for (const auto& p : spec.processes)
        if (seen_.count(p)) where += " " + p + "@" + std::to_string(seen_[p].step);
      std::string lacking;
      for (const auto& [channel, range] : edge_.missingRanges())
        lacking += " " + channel + " " + std::to_string(range.first) + ".." + std::to_string(range.second - 1);
      return {false, "stalled: no progress for " + std::to_string(static_cast<int>(spec.stall_seconds)) +
                         " s (last step handled per process:" + where + ")" + stuckProcesses() +
                         (lacking.empty() ? "" : "; the runner still misses" + lacking) +
                         (resultIn() ? "; the run's result is in, not yet the logger's log: " + loggerBehind() : "") +
                         foreign()};
    }
  }
  if (out.run_seconds == 0) out.run_seconds = std::chrono::duration<double>(Clock::now() - started).count();
  return {};
}

// 4. STOP, and the logger closes the log. It is waited for while its log grows (started again after the STOP,
// it goes on from its segments) and while it is silent for less than the run's stall bound (killed and not
// started yet, or paused). Heard but not moving for close_timeout_ms (counted from when it was last heard anew),
// or silent longer, it fails the run, saying where its log stands.
RunDriver::Ending RunDriver::stopAndWait(const Waiting& w, bool patient) {
  closing_ = logged() && (phase_ == Phase::Running || loggerJoined());
  phase_ = Phase::Stopping;
  sendOurs(run_control_t::STOP);
  const ProtocolConfig& protocol = config_.protocol;
  const auto fresh = milliseconds(3 * protocol.heartbeat_ms);  // heard within three heartbeats: alive
  const auto close_timeout = milliseconds(protocol.close_timeout_ms);
  const auto seconds = [](Clock::duration d) { return fmt::format("{:.1f}", std::chrono::duration<double>(d).count()); };
  auto moved_at = Clock::now();  // its log last grew (or the wait began)
  auto back_at = moved_at;       // it was last heard anew (after a silence, or started again)
  std::int64_t extent = -1;      // the most its STATUS said its log holds
  Clock::time_point heard{};
  int pid = 0;
  while (closing_ && !logger_done_) {
    if (auto h = w.health(); !h.empty()) return {false, h};
    if (auto f = failedProcess(); !f.empty()) return {false, f};
    w.pump();
    const auto now = Clock::now();
    const Seen& s = seen_["logger"];
    if (s.pid != pid || s.at - heard > fresh) back_at = s.at;
    heard = s.at;
    pid = s.pid;
    if (ourRequest(s) && s.taken > extent) {
      extent = s.taken;
      moved_at = now;
    }
    const bool wait_silent = patient && !stopRequested();
    const auto bound = wait_silent ? std::chrono::duration_cast<Clock::duration>(
                                         std::chrono::duration<double>(spec_->stall_seconds))
                                   : Clock::duration(close_timeout);
    if (now - s.at > fresh && now - s.at > bound)
      return {false, "the logger has not been heard for " + seconds(now - s.at) + " s (" +
                         (wait_silent ? "the run's --stall-seconds" : "protocol.close_timeout_ms") +
                         ") and has not closed the run's log: " + loggerBehind()};
    if (now - s.at <= fresh && now - std::max(moved_at, back_at) > close_timeout)
      return {false, "the logger has made no progress for " + seconds(now - std::max(moved_at, back_at)) +
                         " s (protocol.close_timeout_ms) and has not closed the run's log: " + loggerBehind()};
  }
  return {};
}

bool RunDriver::loggerHolds() const {
  if (!loggerJoined()) return false;
  for (const auto& [channel, count] : published_)
    if (const auto it = logged_.find(channel); it == logged_.end() || it->second < count) return false;
  return true;
}

bool RunDriver::awaitingSilent(const std::function<bool(const Seen&)>& pred) const {
  const auto now = Clock::now();
  const auto fresh = milliseconds(3 * config_.protocol.heartbeat_ms);
  const auto stall = std::chrono::duration<double>(spec_->stall_seconds);
  for (const auto& p : spec_->processes)
    if (const auto it = seen_.find(p); it != seen_.end() && !pred(it->second) && now - it->second.at > fresh &&
                                       now - it->second.at < stall)
      return true;
  return false;
}

std::int64_t RunDriver::progressOf(const std::function<bool(const Seen&)>& pred) const {
  std::int64_t holding = 0, moves = 0;
  for (const auto& p : spec_->processes)
    if (const auto it = seen_.find(p); it != seen_.end()) {
      holding += pred(it->second) ? 1 : 0;
      moves += it->second.moves;
    }
  return holding + moves * static_cast<std::int64_t>(spec_->processes.size() + 1);
}

// "it was running in the run at step 2999; its log holds 21400 of the 21903 messages its publishers said they
// published (SCENE from 1480 of 1502, ...)"
std::string RunDriver::loggerBehind() const {
  const auto it = seen_.find("logger");
  if (it == seen_.end()) return "it was never heard";
  const Seen& l = it->second;
  const char* states[] = {"waiting", "ready", "running", "done", "failed"};
  std::string said = std::string("it was ") + (l.state >= 0 && l.state < 5 ? states[l.state] : "?") +
                     (ourRequest(l) ? " in the run at step " + std::to_string(l.step) : " (not in the run)");
  std::int64_t held = 0, published = 0;
  std::string behind;
  for (const auto& [channel, count] : published_) {
    const auto at = logged_.find(channel);
    const std::int64_t from = at == logged_.end() ? 0 : at->second;
    held += std::min(from, count);
    published += count;
    if (from < count)
      behind += (behind.empty() ? "" : ", ") + channel + " from " + std::to_string(from) + " of " + std::to_string(count);
  }
  if (published > 0)
    said += "; its log holds " + std::to_string(held) + " of the " + std::to_string(published) +
            " messages its publishers said they published" + (behind.empty() ? "" : " (" + behind + ")");
  return said;
}

}  // namespace afford
