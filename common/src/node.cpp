#include "afford/node.hpp"

#include <cstdlib>
#include <filesystem>

#include <CLI/CLI.hpp>
#include <opencv2/core.hpp>
#include <malloc.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>

#include "afford/bus.hpp"
#include "afford/protocol.hpp"
#include "afford/logging.hpp"

namespace afford {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

NodeBase::NodeBase(lcm::LCM& lcm, std::string process, std::shared_ptr<spdlog::logger> log,
                   const ProtocolConfig& protocol)
    : lcm_(lcm), log_(std::move(log)), process_(std::move(process)), edge_(lcm, log_, process_, protocol) {
  edge_.subscribe(ch::runConfig, [this](const run_config_t& m, const Envelope& e) { return onRunConfig(m, e); }, Scope::Any,
      Order::None);
  edge_.subscribe(ch::runControl, [this](const run_control_t& m, const Envelope& e) { return onRunControl(m, e); },
      Scope::Any, Order::None);
  edge_.subscribe(ch::status, [this](const process_status_t& m) { return onStatus(m); }, Scope::Any, Order::None);
  edge_.answerResends();
  edge_.onFailure([this](const std::string& channel, const std::string& why) { failRun(channel + ": " + why); });
}

Turn NodeBase::onRunConfig(const run_config_t& msg, const Envelope& envelope) {
  if (state_ != process_status_t::WAITING) {
    if (msg.run_id == run_id_) {
      if (msg.digest != run_msg_.digest)
        return Turn::refuse("a configuration of run '" + msg.run_id + "' other than the one this process took");
      publishStatus();  // a repeated config: confirm we have it
      onControl(envelope);
      return Turn::take();
    }
    log_->debug("RUN_CONFIG: run '{}' ignored: this process serves run '{}'", msg.run_id, run_id_);
    return Turn::take();
  }
  try {
    RunConfig cfg = parseRunConfigText(msg.config_yaml);
    if (cfg.seed != msg.seed || toString(cfg.system) != msg.system || cfg.experiment != msg.experiment)
      throw ConfigError("message fields (seed, system, experiment) disagree with config_yaml");
    if (!wantsRun(cfg)) {
      log_->info("run '{}' is not for this process (run.record: false): staying free", msg.run_id);
      return Turn::take();
    }
    config_ = std::move(cfg);
    run_msg_ = msg;
    run_id_ = msg.run_id;
    last_step_ = -1;
    detail_.clear();
    edge_.join(run_id_, &config_);
    for (const auto& clear : joins_) clear();
    onConfigured(config_);
    onControl(envelope);
  } catch (const std::exception& e) {
    edge_.leave();
    run_id_.clear();
    log_->error("RUN_CONFIG: rejected run '{}': {}", msg.run_id, e.what());
    detail_ = e.what();
    state_ = process_status_t::WAITING;
    process_status_t st;
    st.run_id = msg.run_id;
    st.step = -1;
    st.process = process_;
    st.pid = static_cast<int32_t>(getpid());
    st.beat = beat_++;
    st.state = process_status_t::FAILED;
    st.config_digest = msg.digest;  // the configuration refused
    st.detail = detail_.substr(0, static_cast<std::size_t>(protocol().limits.text_bytes));
    st.n_channels = 0;  // nothing published in that run
    edge_.send(ch::status, st);
    return Turn::take();
  }
  log_->info("configured for run '{}' ({} {} seed {}, {} steps)", run_id_, msg.experiment, msg.system, msg.seed,
             config_.steps);
  setState(process_status_t::READY);
  return Turn::take();
}

Turn NodeBase::onRunControl(const run_control_t& msg, const Envelope& envelope) {
  if (run_id_.empty() || msg.run_id != run_id_) {
    log_->debug("RUN_CONTROL: for run '{}', not this process's", msg.run_id);
    return Turn::take();
  }
  onControl(envelope);
  if (msg.command == run_control_t::START) {
    if (state_ != process_status_t::READY) return Turn::take();  // already started: idempotent
    setState(process_status_t::RUNNING);
    onStart();
    edge_.retry();  // messages that came before START
  } else {
    if (readyToLeave()) {
      leaveRun();
      return Turn::take();
    }
    if (!stop_pending_) stop_deadline_ = Clock::now() + milliseconds(protocol().stop_grace_ms);
    stop_pending_ = true;
  }
  return Turn::take();
}

Turn NodeBase::onStatus(const process_status_t& st) {
  if (st.process == process_ && st.pid == getpid()) return Turn::take();  // our own
  edge_.claim(st);
  onPeerStatus(st);
  // A process that has just (re)joined our run catches up from what we say we published.
  const bool joined = !run_id_.empty() && st.run_id == run_id_ && st.step == -1 &&
                      (st.state == process_status_t::READY || st.state == process_status_t::RUNNING);
  if (joined && !edge_.counts().empty() && Clock::now() - announced_at_ >= milliseconds(protocol().idle_announce_ms))
    publishStatus();
  return Turn::take();
}

void NodeBase::leaveRun() {
  if (state_ == process_status_t::WAITING) return;
  try {
    onStop();
  } catch (const std::exception& e) {
    log_->error("leaving run '{}': {}", run_id_, e.what());
    detail_ = e.what();
  }
  log_->info("left run '{}' at step {} (it waits {:.2f} ms for an input, usually)", run_id_, last_step_,
             std::chrono::duration<double, std::milli>(edge_.usualWait()).count());
  stop_pending_ = false;
  edge_.leave();
  run_id_.clear();
  last_step_ = -1;
  setState(process_status_t::WAITING, detail_);
}

void NodeBase::setState(int8_t state, const std::string& detail) {
  state_ = state;
  detail_ = detail;
  publishStatus();
}

void NodeBase::failRun(const std::string& why) {
  if (run_id_.empty()) return log_->error("{}", why);
  log_->error("run '{}' failed here: {}", run_id_, why);
  edge_.suspend();
  setState(process_status_t::FAILED, why);
}

void NodeBase::publishStatus() {
  process_status_t st;
  st.run_id = run_id_;
  st.step = last_step_;
  st.process = process_;
  st.pid = static_cast<int32_t>(getpid());
  st.beat = beat_++;
  st.state = state_;
  st.config_digest = run_id_.empty() ? 0 : run_msg_.digest;
  st.detail = detail_.substr(0, static_cast<std::size_t>(protocol().limits.text_bytes));
  st.counts_run = edge_.historyRun();
  for (const auto& [channel, n] : edge_.counts()) {
    st.channels.push_back(channel);
    st.counts.push_back(n);
  }
  st.n_channels = static_cast<int32_t>(st.channels.size());
  edge_.send(ch::status, st);
  const auto now = Clock::now();
  next_beat_ = now + milliseconds(protocol().heartbeat_ms);
  announced_at_ = now;
}

void NodeBase::tick() {
  const auto now = Clock::now();
  if (now >= next_beat_) publishStatus();
  const bool in_run = state_ == process_status_t::RUNNING || state_ == process_status_t::DONE;
  if (in_run && !edge_.counts().empty()) {
    // Idle after publishing: say what we published, in case the last of it was lost.
    const auto idle = idleAnnounceAfter();
    if (edge_.lastActivity() > announced_at_ || announce_wait_ == Clock::duration{}) announce_wait_ = idle;
    if (now - edge_.lastActivity() >= idle && now - announced_at_ >= announce_wait_) {
      const auto wait = announce_wait_;
      publishStatus();
      edge_.waitAnnounced();
      announce_wait_ = std::min<Clock::duration>(wait * 2, milliseconds(protocol().heartbeat_ms));
    }
  }
  if (!run_id_.empty()) edge_.askMissing();
  if (stop_pending_ && (readyToLeave() || now > stop_deadline_)) {
    if (!readyToLeave()) onLeaveTimeout();
    leaveRun();
  }
}

auto NodeBase::idleAnnounceAfter() const -> Clock::duration {
  const Clock::duration least = milliseconds(protocol().idle_announce_ms);
  return std::min<Clock::duration>(std::max(least, edge_.usualWait() * protocol().idle_announce_pace),
                                   std::max<Clock::duration>(least, milliseconds(protocol().heartbeat_ms)));
}

int NodeBase::msUntilDue() const {
  const auto now = Clock::now();
  Clock::time_point due = std::min(next_beat_, edge_.nextDue());
  if ((state_ == process_status_t::RUNNING || state_ == process_status_t::DONE) && !edge_.counts().empty()) {
    const auto idle = idleAnnounceAfter();
    due = std::min(due, std::max(edge_.lastActivity() + idle, announced_at_ + std::max<Clock::duration>(announce_wait_, idle)));
  }
  if (stop_pending_) due = std::min(due, stop_deadline_);
  const auto ms = std::chrono::duration_cast<milliseconds>(due - now).count();
  return static_cast<int>(std::clamp<long long>(ms, 1, 100));
}

}  // namespace afford
