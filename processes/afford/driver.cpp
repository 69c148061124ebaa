#include "afford/driver.hpp"

#include <algorithm>

#include "afford/affordance_table_t.hpp"
#include "afford/channels.hpp"
#include "afford/extrinsic_result_t.hpp"
#include "afford/node.hpp"
#include "afford/process_status_t.hpp"
#include "afford/run_config_t.hpp"
#include "afford/run_control_t.hpp"
#include "afford/run_result_t.hpp"

namespace afford {

using Clock = std::chrono::steady_clock;

RunDriver::RunDriver(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log) : lcm_(lcm), log_(std::move(log)) {
  listen(channel::kStatus, [this](const lcm::ReceiveBuffer* b) {
    process_status_t m;
    std::string why;
    if (!decodeAtEdge(b, m, why)) return log_->warn("{}: dropped message: {}", channel::kStatus, why);
    seen_[m.process] = {m.run_id, m.step, m.state, m.detail, Clock::now()};
    if (outcome_ && m.counts_run == run_id_) {
      for (int i = 0; i < m.n_channels; ++i)
        if (m.channels[i] == channel::kAffordanceTable || m.channels[i] == channel::kResult ||
            m.channels[i] == channel::kExtrinsicResult)
          serials_.announce(m.channels[i], m.counts[i]);
    }
    if (outcome_ && m.process == "logger" && m.run_id == run_id_ && m.state == process_status_t::DONE) {
      outcome_->log_dir = m.detail;
      logger_done_ = true;
    }
  });
  listen(channel::kAffordanceTable, [this](const lcm::ReceiveBuffer* b) {
    affordance_table_t m;
    std::string why;
    if (!decodeAtEdge(b, m, why)) return log_->warn("{}: dropped message: {}", channel::kAffordanceTable, why);
    if (!outcome_ || m.run_id != run_id_ || !inOrder(channel::kAffordanceTable, m.serial)) return;
    outcome_->curve.push_back({m.step, m.affordance});
  });
  listen(channel::kExtrinsicResult, [this](const lcm::ReceiveBuffer* b) {
    extrinsic_result_t m;
    std::string why;
    if (!decodeAtEdge(b, m, why)) return log_->warn("{}: dropped message: {}", channel::kExtrinsicResult, why);
    if (!outcome_ || m.run_id != run_id_ || !inOrder(channel::kExtrinsicResult, m.serial)) return;
    ExtrinsicOutcome& e = outcome_->extrinsic;
    e.scenario = m.scenario;
    e.success = m.success;
    e.completion = m.completion;
    e.attempts = m.attempts;
    e.utility = m.utility;
    for (const auto& g : m.sub_goals)
      e.sub_goals.push_back({g.x, g.y, g.iterations, g.actions_checked, g.actions_taken, g.reached != 0});
    have_result_ = true;
  });
  listen(channel::kResult, [this](const lcm::ReceiveBuffer* b) {
    run_result_t m;
    std::string why;
    if (!decodeAtEdge(b, m, why)) return log_->warn("{}: dropped message: {}", channel::kResult, why);
    if (!outcome_ || m.run_id != run_id_ || !inOrder(channel::kResult, m.serial)) return;
    outcome_->weights_checksum = m.weights_checksum;
    outcome_->checkpoint = m.checkpoint;
    outcome_->executed = m.actions_executed;
    outcome_->successes = m.successes;
    have_result_ = true;
  });
}

void RunDriver::listen(const std::string& channel, std::function<void(const lcm::ReceiveBuffer*)> fn) {
  auto h = std::make_unique<Holder>();
  h->fn = std::move(fn);
  lcm_.subscribe(channel, &Holder::on, h.get())->setQueueCapacity(10000);
  holders_.push_back(std::move(h));
}

bool RunDriver::inOrder(const std::string& channel, std::int64_t serial) {
  const SerialTracker::Verdict v = serials_.offer(channel, serial);
  if (v == SerialTracker::Verdict::Gap) askMissing();
  return v == SerialTracker::Verdict::Accept;
}

void RunDriver::askMissing() {
  for (const SerialTracker::Request& r : serials_.due(Clock::now())) publishResend(lcm_, run_id_, r, "runner");
}

RunOutcome RunDriver::run(const RunSpec& spec, const std::function<void()>& pump,
                          const std::function<std::string()>& health) {
  RunOutcome out;
  const auto t0 = Clock::now();
  run_id_ = spec.run_id;
  outcome_ = &out;
  have_result_ = false;
  logger_done_ = false;
  serials_.reset();
  struct Reset {
    RunDriver* d;
    ~Reset() { d->outcome_ = nullptr; }
  } reset{this};

  auto fail = [&](const std::string& why) {
    out.ok = false;
    out.error = "run '" + spec.run_id + "': " + why;
    out.wall_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    return out;
  };
  auto missing = [&](auto pred) {
    std::string names;
    for (const auto& p : spec.processes)
      if (!seen_.count(p) || !pred(seen_.at(p))) names += (names.empty() ? "" : ", ") + p;
    return names;
  };
  auto failedProcess = [&]() -> std::string {
    for (const auto& p : spec.processes) {
      auto it = seen_.find(p);
      if (it != seen_.end() && it->second.run_id == spec.run_id && it->second.state == process_status_t::FAILED)
        return "process '" + p + "' failed: " + it->second.detail;
    }
    return "";
  };

  // 1. Every process present and free. One still in an earlier run a second
  // from now (its STOP datagram lost; normally its WAITING status is on the
  // way) is told again, once a second.
  auto deadline = t0 + std::chrono::seconds(15);
  auto last_stop = Clock::now();
  while (!missing([](const Seen& s) { return s.state == process_status_t::WAITING && s.run_id.empty(); }).empty()) {
    if (auto h = health(); !h.empty()) return fail(h);
    if (Clock::now() - last_stop > std::chrono::seconds(1)) {
      for (const auto& p : spec.processes) {
        auto it = seen_.find(p);
        if (it == seen_.end() || it->second.run_id.empty() || it->second.run_id == spec.run_id) continue;
        run_control_t stop;
        stop.run_id = it->second.run_id;
        stop.step = 0;
        stop.command = run_control_t::STOP;
        lcm_.publish(channel::kRunControl, &stop);
        log_->warn("process '{}' is still in run '{}': told to stop again", p, it->second.run_id);
      }
      last_stop = Clock::now();
    }
    if (Clock::now() > deadline)
      return fail("no process of this name reported ready for a run within 15 s: " +
                  missing([](const Seen& s) { return s.state == process_status_t::WAITING && s.run_id.empty(); }));
    pump();
  }

  // 2. Configure.
  run_config_t cfg;
  cfg.run_id = spec.run_id;
  cfg.step = 0;
  cfg.seed = spec.seed;
  cfg.experiment = spec.experiment;
  cfg.system = spec.system;
  cfg.config_yaml = spec.config_yaml;
  lcm_.publish(channel::kRunConfig, &cfg);
  auto last_send = Clock::now();
  deadline = Clock::now() + std::chrono::seconds(15);
  auto ready = [&](const Seen& s) { return s.run_id == spec.run_id && s.state == process_status_t::READY; };
  while (!missing(ready).empty()) {
    if (auto h = health(); !h.empty()) return fail(h);
    if (auto f = failedProcess(); !f.empty()) return fail(f);
    if (Clock::now() > deadline) return fail("not configured within 15 s: " + missing(ready));
    if (Clock::now() - last_send > std::chrono::seconds(2)) {  // a lost datagram: say it again
      lcm_.publish(channel::kRunConfig, &cfg);
      last_send = Clock::now();
    }
    pump();
  }

  // 3. Run.
  run_control_t start;
  start.run_id = spec.run_id;
  start.step = 0;
  start.command = run_control_t::START;
  lcm_.publish(channel::kRunControl, &start);
  const auto started = Clock::now();
  std::int64_t progress = -1;
  auto progress_at = Clock::now();
  auto last_rejoin = Clock::now() - std::chrono::seconds(10);
  // A process that was killed can be started again: it is silent meanwhile.
  const auto silence = std::chrono::duration<double>(spec.stall_seconds);
  const bool logged = std::find(spec.processes.begin(), spec.processes.end(), "logger") != spec.processes.end();
  // The logger must be in the run to close its log: one restarted after the
  // last step still catches up first.
  auto loggerIn = [&] { return !logged || (seen_.count("logger") && seen_["logger"].run_id == spec.run_id); };
  while (!have_result_ || !loggerIn()) {
    if (auto h = health(); !h.empty()) return fail(h);
    if (auto f = failedProcess(); !f.empty()) return fail(f);
    pump();
    askMissing();
    const auto now = Clock::now();
    std::int64_t step = -1, handled = 0;  // the furthest step; the steps of all, in the run
    std::string rejoining;
    for (const auto& p : spec.processes) {
      auto it = seen_.find(p);
      if (it == seen_.end()) continue;
      if (now - it->second.at > silence)
        return fail("process '" + p + "' stopped reporting (last heard " +
                    std::to_string(std::chrono::duration<double>(now - it->second.at).count()) + " s ago)");
      if (it->second.run_id.empty() && it->second.state == process_status_t::WAITING)
        rejoining += (rejoining.empty() ? "" : ", ") + p;
      step = std::max(step, it->second.step);
      if (it->second.run_id == spec.run_id) handled += it->second.step + 1;
    }
    // A process of the run is free (restarted): give it the run again.
    if (!rejoining.empty() && now - last_rejoin > std::chrono::seconds(1)) {
      log_->warn("run '{}': process {} is free again (restarted?) at step {}: sending it the run's configuration",
                 spec.run_id, rejoining, step);
      lcm_.publish(channel::kRunConfig, &cfg);
      lcm_.publish(channel::kRunControl, &start);
      last_rejoin = now;
    }
    // Progress is any process moving on, a restarted one catching up included.
    if (handled != progress) {
      progress = handled;
      progress_at = now;
    } else if (now - progress_at > std::chrono::duration<double>(spec.stall_seconds)) {
      std::string where;
      for (const auto& p : spec.processes)
        if (seen_.count(p)) where += " " + p + "@" + std::to_string(seen_[p].step);
      return fail("stalled: no progress for " + std::to_string(static_cast<int>(spec.stall_seconds)) +
                  " s (last step handled per process:" + where + ")");
    }
  }

  out.run_seconds = std::chrono::duration<double>(Clock::now() - started).count();

  // 4. Stop, and let the logger close the log.
  run_control_t stop = start;
  stop.command = run_control_t::STOP;
  stop.step = spec.steps;
  lcm_.publish(channel::kRunControl, &stop);
  deadline = Clock::now() + std::chrono::seconds(15);
  while (logged && !logger_done_) {
    if (auto h = health(); !h.empty()) return fail(h);
    if (Clock::now() > deadline) return fail("the logger did not close the log within 15 s");
    pump();
  }
  out.ok = true;
  out.wall_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return out;
}

}  // namespace afford
