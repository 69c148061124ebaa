#include "experiment/run/driver.hpp"

#include "afford/names.hpp"

#include <spdlog/fmt/fmt.h>

#include <algorithm>
#include <filesystem>

#include "afford/affordance_table_t.hpp"
#include "afford/protocol.hpp"
#include "afford/processes.hpp"
#include "afford/extrinsic_result_t.hpp"
#include "afford/node.hpp"
#include "afford/process_main.hpp"
#include "afford/process_status_t.hpp"
#include "afford/run_config_t.hpp"
#include "afford/run_control_t.hpp"
#include "afford/run_result_t.hpp"

namespace afford {

using std::chrono::milliseconds;

namespace {

// Where the run's messages meet its outcome: one converter per pair.
TableSnapshot snapshotOf(const affordance_table_t& m) { return {m.step, m.affordance}; }

ExtrinsicOutcome extrinsicOutcomeOf(const extrinsic_result_t& m) {
  ExtrinsicOutcome e;
  e.scenario = m.scenario;
  e.success = m.success;
  e.completion = m.completion;
  e.attempts = m.attempts;
  e.utility = m.utility;
  for (const sub_goal_t& g : m.sub_goals)
    e.sub_goals.push_back({g.x, g.y, g.iterations, g.actions_checked, g.actions_taken, g.reached != 0});
  return e;
}

// RESULT's counts (its checksum and checkpoint are checked by the driver).
void takeCounts(RunOutcome& o, const run_result_t& m) {
  o.executed = m.actions_executed;
  o.successes = m.successes;
  o.looks = m.looks;
  o.replayed = m.replayed;
  o.replayed_effects = m.replayed_effects;
  o.revisits = m.revisits;
}

// A goal's end into the bins of its curve interval (the goals the run's end cut short: the last one's).
void takeGoal(std::vector<GoalBin>& bins, const goal_result_t& m, std::int64_t interval, std::int64_t steps) {
  const std::int64_t step = std::min(m.step, std::max<std::int64_t>(0, steps - 1)) / interval * interval;
  if (bins.empty() || bins.back().step != step) {
    GoalBin b;
    b.step = step;
    b.set = b.reached = b.actions = b.found = std::vector<std::int64_t>(4, 0);
    bins.push_back(std::move(b));
  }
  const auto module = static_cast<std::size_t>(m.module);  // checked on the edge: 0 to 3
  ++bins.back().set[module];
  bins.back().reached[module] += m.reached ? 1 : 0;
  bins.back().actions[module] += m.actions;
  bins.back().found[module] += m.reached && m.actions == 0 ? 1 : 0;
}

}  // namespace

RunDriver::RunDriver(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol)
    : lcm_(lcm),
      log_(std::move(log)),
      edge_(lcm, log_, "runner", protocol),
      runners_(edge_, log_, protocol),
      silence_(log_, milliseconds(6 * protocol.heartbeat_ms)) {
  edge_.warnOtherRuns(false);  // late messages of the slot's previous run are normal
  edge_.subscribe(ch::status, [this](const process_status_t& m) { return onStatus(m); }, Scope::Any, Order::None);
  edge_.subscribe(ch::affordanceTable,
      [this](const affordance_table_t& m) {
        if (!outcome_) return Turn::take();
        outcome_->curve.push_back(snapshotOf(m));
        if (on_table_) on_table_(outcome_->curve.back());
        return Turn::take();
      },
      Scope::Run, Order::Serial);
  edge_.subscribe(ch::extrinsicResult,
      [this](const extrinsic_result_t& m) {
        if (!outcome_) return Turn::take();
        outcome_->extrinsic = extrinsicOutcomeOf(m);
        have_result_ = true;
        return Turn::take();
      },
      Scope::Run, Order::Serial);
  edge_.subscribe(ch::goalResult,
      [this](const goal_result_t& m) {
        if (!outcome_) return Turn::take();
        takeGoal(outcome_->goals, m, config_.curve_interval, config_.steps);
        goals_ended_ = goals_ended_ || m.step >= config_.steps;
        return Turn::take();
      },
      Scope::Run, Order::Serial);
  edge_.subscribe(ch::result,
      [this](const run_result_t& m) {
        if (!outcome_) return Turn::take();
        outcome_->weights_checksum = m.weights_checksum;
        // Only the checkpoint the run was configured with (the predictors report it, or "" if they could not write it).
        if (m.checkpoint.empty() || m.checkpoint == config_.checkpoint)
          outcome_->checkpoint = m.checkpoint;
        else
          log_->warn("RESULT of run '{}' names the checkpoint '{}', not the run's: not taken", m.run_id,
                     printable(m.checkpoint));
        takeCounts(*outcome_, m);
        have_result_ = true;
        return Turn::take();
      },
      Scope::Run, Order::Serial);
}

bool RunDriver::isRunFolder(const std::string& folder) const {
  namespace fs = std::filesystem;
  std::error_code ec;
  return spec_ && !folder.empty() &&
         fs::weakly_canonical(fs::absolute(folder, ec), ec) ==
             fs::weakly_canonical(fs::absolute(fs::path(spec_->log_root) / spec_->run_id, ec), ec);
}

bool RunDriver::ours(const std::string& process) const {
  return spec_ && std::find(spec_->processes.begin(), spec_->processes.end(), process) != spec_->processes.end();
}

void RunDriver::sendControl(const std::string& run_id, int8_t command, std::int64_t config_digest) {
  run_control_t c{};
  c.run_id = run_id;
  c.step = command == run_control_t::STOP && spec_ && run_id == spec_->run_id ? spec_->steps : 0;
  c.command = command;
  c.config_digest = config_digest;
  edge_.send(ch::runControl, c);
}

bool RunDriver::ourRequest(const Seen& s) const {
  return spec_ && s.run_id == spec_->run_id && s.config_digest == config_msg_.digest;
}

Turn RunDriver::onStatus(const process_status_t& m) {
  if (runners_.heard(m)) return Turn::take();  // another runner's beat
  if (!isProcessName(m.process)) return Turn::take();  // not one of ours (a tool, or a forgery)
  if (runners_.refusingCopy(m)) return Turn::take();  // a copy that refuses to serve: not the run's
  Seen& s = seen_[m.process];
  std::int64_t taken = 0;
  for (int i = 0; i < m.n_takes; ++i) taken += m.takes_from[i];
  if (s.pid == m.pid && s.run_id == m.run_id && s.config_digest == m.config_digest && (m.step > s.step || taken > s.taken))
    ++s.moves;
  s.run_id = m.run_id;
  s.step = m.step;
  s.state = m.state;
  s.pid = m.pid;
  s.config_digest = m.config_digest;
  s.detail = m.detail;
  s.stuck = m.stuck;
  s.at = Clock::now();
  s.counts_run = m.counts_run;
  s.counts_config = m.counts_config;
  s.taken = taken;
  if (spec_ && m.counts_run == spec_->run_id && m.counts_config == config_msg_.digest)
    for (int i = 0; i < m.n_channels; ++i)
      if (publisherOf(m.channels[i], config_.phase) == m.process) {  // only a channel's publisher speaks for it
        std::int64_t& most = published_[m.channels[i]];
        most = std::max(most, m.counts[i]);
      }
  if (m.process == "logger" && ourRequest(s))
    for (int i = 0; i < m.n_takes; ++i) logged_[m.takes[i]] = m.takes_from[i];
  edge_.claim(m);
  if (phase_ == Phase::Idle || !spec_) return Turn::take();
  if (on_step_ && phase_ == Phase::Running && ourRequest(s) && m.step >= 0 && ours(m.process)) on_step_(m.step);
  // The logger closed the log: it says DONE with the log's folder, then, free
  // again, the run it left (its DONE may have been lost on the way).
  const bool closed = m.state == process_status_t::DONE && ourRequest(s);
  const bool left = phase_ == Phase::Stopping && m.state == process_status_t::WAITING && m.run_id.empty() &&
                    m.counts_run == spec_->run_id && m.counts_config == config_msg_.digest &&
                    std::filesystem::is_directory(m.detail);
  if (m.process == "logger" && (closed || left) && outcome_) {
    // The run's log folder is the one under the runner's --log-root, whatever a message names.
    if (isRunFolder(m.detail))
      outcome_->log_dir = m.detail;
    else if (!logger_done_)
      log_->info("the logger closed the log of run '{}' in '{}', not in {}/: not kept as the run's log folder",
                 spec_->run_id, printable(m.detail), spec_->log_root);
    logger_done_ = true;
  }
  if (ours(m.process) && !runners_.anotherServes(m, spec_->run_id, config_msg_.digest)) nudge(m.process, s);
  return Turn::take();
}

void RunDriver::nudge(const std::string& process, const Seen& s) {
  const std::string& run = spec_->run_id;
  const bool free = s.run_id.empty() && s.state == process_status_t::WAITING;
  // In another request of this run id (a recording played back, an earlier runner's): it is told to leave it,
  // so that it takes ours; what that request publishes follows no chain of ours and is dropped.
  const bool other_request = s.run_id == run && s.config_digest != config_msg_.digest && s.state != process_status_t::FAILED;
  const auto now = Clock::now();
  auto& last = nudged_[process];
  if (now - last < milliseconds(config_.protocol.retry_ms)) return;  // told a moment ago: the answer is on its way
  const auto leave = [&] {
    if (!runners_.settled()) return;  // another runner may drive that run: not before it could have been heard
    if (other_request) {
      ++foreign_[process];
      if (warned_.insert({process + " another", s.pid}).second)
        log_->info("run '{}': process {} (pid {}) holds another request of this run id: told to leave it", run,
                   process, s.pid);
    }
    sendControl(s.run_id, run_control_t::STOP, s.config_digest);
    last = now;
  };
  switch (phase_) {
    case Phase::Freeing:
      // Still in another run (or request) a while after this one began (its WAITING is not simply on its way):
      // its STOP was lost, or it serves a run nobody runs.
      if (!s.run_id.empty() && (s.run_id != run || other_request) &&
          now - phase_at_ >= milliseconds(config_.protocol.retry_ms) && runners_.settled()) {
        if (warned_.insert({process + " in " + s.run_id, s.pid}).second)
          log_->warn("process '{}' is still in run '{}': told to stop again", process, s.run_id);
        leave();
      }
      return;
    case Phase::Configuring:
      if (free) {  // it has not had the configuration (lost, or it started after it went out)
        edge_.send(ch::runConfig, config_msg_);
        last = now;
      } else if (!s.run_id.empty() && (s.run_id != run || other_request)) {
        leave();
      }
      return;
    case Phase::Running:
      if (free) {  // restarted: give it the run again; it catches up
        std::int64_t step = -1;
        for (const auto& [p, other] : seen_)
          if (ourRequest(other)) step = std::max(step, other.step);
        if (warned_.insert({process, s.pid}).second)
          log_->warn("run '{}': process {} is free again (restarted?) at step {}: sending it the run's configuration",
                     run, process, step);
        edge_.send(ch::runConfig, config_msg_);
        sendOurs(run_control_t::START);
        last = now;
      } else if (ourRequest(s) && s.state == process_status_t::READY) {  // its START was lost
        sendOurs(run_control_t::START);
        last = now;
      } else if (other_request) {
        leave();
      }
      return;
    case Phase::Stopping:
      // The logger killed after the STOP, before it closed the log (its log held all that was published: the
      // STOP waited for it), and started again: it is given the run again (the free processes take it too, and
      // leave it on the STOP that follows: no START), goes on from its log's segments, and closes the log on the
      // STOP. (Free with our request's counts, it has left the run: its log is closed.)
      if (process == "logger" && closing_ && !logger_done_ && !stopRequested()) {
        if (free && !(s.counts_run == run && s.counts_config == config_msg_.digest)) {
          if (warned_.insert({process + " closing", s.pid}).second)
            log_->warn("run '{}': the logger is free again (restarted?) before it closed the run's log: sending it "
                       "the run's configuration", run);
          edge_.send(ch::runConfig, config_msg_);
          last = now;
          return;
        }
      }
      if (ourRequest(s) && s.state != process_status_t::FAILED) {  // its STOP was lost
        sendOurs(run_control_t::STOP);
        last = now;
      }
      return;
    case Phase::Idle:
      return;
  }
}

bool RunDriver::logged() const {
  return std::find(spec_->processes.begin(), spec_->processes.end(), "logger") != spec_->processes.end();
}

bool RunDriver::loggerJoined() const {
  const auto it = seen_.find("logger");
  return it != seen_.end() && ourRequest(it->second);
}

std::string RunDriver::missing(const std::function<bool(const Seen&)>& pred) const {
  std::string names;
  for (const auto& p : spec_->processes)
    if (!seen_.count(p) || !pred(seen_.at(p))) names += (names.empty() ? "" : ", ") + p;
  return names;
}

std::string RunDriver::failedProcess() const {
  for (const auto& p : spec_->processes) {
    auto it = seen_.find(p);
    if (it == seen_.end() || it->second.run_id != spec_->run_id || it->second.state != process_status_t::FAILED) continue;
    if (it->second.config_digest != config_msg_.digest) continue;  // about a configuration that is not ours
    // Once the result is in, a process that fails afterwards (restarted after its
    // last step, it refuses to save its weights again) changes nothing; the logger does.
    if (have_result_ && p != "logger") continue;
    return "process '" + p + "' failed: " + it->second.detail;
  }
  return "";
}

// The processes that took a configuration of this run other than ours, and were told to leave it.
std::string RunDriver::foreign() const {
  std::string said;
  for (const auto& [p, times] : foreign_)
    said += (said.empty() ? "" : ", ") + p + " (" + std::to_string(times) + (times == 1 ? " time)" : " times)");
  return said.empty() ? ""
                      : "; told to leave another configuration of this run id: " + said +
                            " (another publisher on the bus sends RUN_CONFIG with this run id)";
}

// What each process of the run could not take when it last said so: where the chain broke, and why.
std::string RunDriver::stuckProcesses() const {
  std::string said;
  for (const auto& p : spec_->processes) {
    const auto it = seen_.find(p);
    if (it == seen_.end() || !ourRequest(it->second) || it->second.stuck.empty()) continue;
    said += "; " + p + " cannot take " + it->second.stuck;
    // The same message at its serial, refused again and again: its publisher gives, for that serial, a message
    // other than the one taken before it (a restarted component that does not compute what it computed).
    if (it->second.stuck.find("prev_digest does not follow") != std::string::npos)
      said += " (its publisher, asked again, sends a message other than the one that followed the message taken "
              "before it: a restarted component that does not compute what it computed before, e.g. randomness "
              "not keyed by the run's seed, step and purpose)";
  }
  return said;
}

RunOutcome& RunDriver::failed(const std::string& why) {
  RunOutcome& out = *outcome_;
  out.ok = false;
  out.error = "run '" + spec_->run_id + "': " + why;
  if (phase_ != Phase::Freeing) {
    phase_ = Phase::Stopping;
    sendOurs(run_control_t::STOP);  // no process stays in a failed run
  }
  out.wall_seconds = std::chrono::duration<double>(Clock::now() - started_at_).count();
  return out;
}

RunOutcome& RunDriver::interrupted(const Waiting& w) {
  // The furthest step the run is known to have reached: its processes' heartbeats, and its curve's last table
  // (a run stopped at a curve point, as a pruned one is, may be there before any heartbeat says so).
  std::int64_t step = outcome_->curve.empty() ? -1 : outcome_->curve.back().step;
  for (const auto& [p, s] : seen_)
    if (ourRequest(s)) step = std::max(step, s.step);
  stopAndWait(w, /*patient=*/false);
  RunOutcome& out = *outcome_;
  out.ok = false;
  out.interrupted = true;
  out.error = "run '" + spec_->run_id + "': interrupted at step " + std::to_string(step);
  out.wall_seconds = std::chrono::duration<double>(Clock::now() - started_at_).count();
  return out;
}

RunOutcome RunDriver::run(const RunSpec& spec, const std::function<void()>& pump,
                          const std::function<std::string()>& health) {
  RunOutcome out;
  started_at_ = Clock::now();
  try {
    config_ = parseRunConfigText(spec.config_yaml);
  } catch (const std::exception& e) {
    out.error = "run '" + spec.run_id + "': " + e.what();
    return out;
  }
  spec_ = &spec;
  outcome_ = &out;
  have_result_ = false;
  goals_ended_ = false;
  logger_done_ = false;
  closing_ = false;
  published_.clear();
  logged_.clear();
  nudged_.clear();
  foreign_.clear();
  warned_.clear();
  config_msg_ = run_config_t();
  config_msg_.run_id = spec.run_id;
  config_msg_.step = 0;
  config_msg_.request = BusKey::newRequest();  // this request's own: nothing said for another is taken for it
  config_msg_.seed = spec.seed;
  config_msg_.experiment = spec.experiment;
  config_msg_.system = spec.system;
  config_msg_.config_yaml = spec.config_yaml;
  sealed(config_msg_);  // its digest: what the processes' STATUS name, and where every chain of the request starts
  edge_.join(spec.run_id, &config_, requestOf(config_msg_));
  struct Reset {
    RunDriver* d;
    ~Reset() {
      d->phase_ = Phase::Idle;
      d->outcome_ = nullptr;
      d->spec_ = nullptr;
      d->edge_.leave();
      d->silence_.reset();
    }
  } reset{this};
  // While it drives, the runner beats; another runner driving the bus, or two copies of a process in the run,
  // end the run as a process gone would (the first stops the experiment: its runs are for another time).
  const std::function<void()> beating = [&] {
    pump();
    if (runners_.due(static_cast<int>(phase_))) runners_.beat(static_cast<int>(phase_), doing());
  };
  const std::function<std::string()> healthy = [&] {
    if (const std::string& r = runners_.refusal(); !r.empty()) {
      requestStop("another runner on this bus");  // (the experiment is "interrupted by" it; the run says who)
      return r;
    }
    const std::string mixed = runners_.mixed(spec.run_id, config_msg_.digest, spec.processes);
    return mixed.empty() ? health() : mixed;
  };
  const Waiting w{beating, healthy};
  for (auto stage : {&RunDriver::waitFree, &RunDriver::configure, &RunDriver::runSteps}) {
    const Ending e = (this->*stage)(w);
    if (e.interrupted) return interrupted(w);
    if (!e.why.empty()) return failed(e.why);
  }
  // 4. Stop, and let the logger close the log.
  if (const Ending e = stopAndWait(w, /*patient=*/true); !e.why.empty()) return failed(e.why);
  if (auto f = failedProcess(); !f.empty()) return failed(f);
  out.ok = true;
  out.wall_seconds = std::chrono::duration<double>(Clock::now() - started_at_).count();
  return out;
}

// What the runner's beat says: its run, the last step reported, what it waits for, who is silent.
RunnerBeat::Doing RunDriver::doing() const {
  RunnerBeat::Doing d;
  if (!spec_) return d;
  d.run_id = spec_->run_id;
  d.request = config_msg_.digest;
  const auto now = Clock::now();
  std::string silent;  // the processes of the run not heard for two heartbeats
  for (const auto& p : spec_->processes) {
    const auto it = seen_.find(p);
    if (it != seen_.end() && ourRequest(it->second)) d.step = std::max(d.step, it->second.step);
    const double quiet = it == seen_.end() ? -1 : std::chrono::duration<double>(now - it->second.at).count();
    if (quiet * 1000 > 2 * config_.protocol.heartbeat_ms)
      silent += fmt::format("{}{} (not heard for {:.1f} s)", silent.empty() ? "" : ", ", p, quiet);
  }
  switch (phase_) {
    case Phase::Freeing:
      d.detail = "waits for these to be free: " + missing([](const Seen& s) {
                   return s.state == process_status_t::WAITING && s.run_id.empty();
                 });
      if (!runners_.settled()) d.detail += " (before it tells one to leave another run, it listens for its runner)";
      break;
    case Phase::Configuring:
      d.detail = "configures the run; waits for READY from: " +
                 missing([&](const Seen& s) { return ourRequest(s) && s.state == process_status_t::READY; });
      break;
    case Phase::Running:
      d.detail = !logged()           ? "runs"
                 : !loggerJoined()     ? "runs; waits for the logger to take the run"
                 : have_result_ && !loggerHolds() ? "the result is in; waits for the logger: its log does not yet hold all that was published"
                                                  : "runs";
      break;
    case Phase::Stopping:
      d.detail = logged() && !logger_done_ ? "stopped the run; waits for the logger to close its log" : "stops the run";
      break;
    case Phase::Idle:
      break;
  }
  if (!silent.empty()) d.detail += "; silent: " + silent;
  return d;
}

}  // namespace afford
