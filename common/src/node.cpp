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
#include "afford/process_main.hpp"
#include "afford/processes.hpp"
#include "afford/protocol.hpp"
#include "afford/logging.hpp"

namespace afford {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

NodeBase::NodeBase(lcm::LCM& lcm, std::string process, std::shared_ptr<spdlog::logger> log,
                   const ProtocolConfig& protocol)
    : lcm_(lcm),
      log_(std::move(log)),
      process_(std::move(process)),
      edge_(lcm, log_, process_, protocol),
      copies_(Instance::self(process_)) {
  edge_.subscribe(ch::runConfig, [this](const run_config_t& m, const Envelope& e) { return onRunConfig(m, e); }, Scope::Any,
      Order::None);
  edge_.subscribe(ch::runControl, [this](const run_control_t& m, const Envelope& e) { return onRunControl(m, e); },
      Scope::Any, Order::None);
  edge_.subscribe(ch::status, [this](const process_status_t& m) { return onStatus(m); }, Scope::Any, Order::None);
  edge_.answerResends();
  edge_.onFailure([this](const std::string& channel, const std::string& why) { failRun(channel + ": " + why); });
  edge_.onQuiet([this] { maybeSnapshot(); });  // between two messages: the place for a snapshot
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
    edge_.join(run_id_, &config_, requestOf(run_msg_));
    for (const auto& clear : joins_) clear();
    onConfigured(config_);
    restoreSnapshot();
    onControl(envelope);
  } catch (const std::exception& e) {
    edge_.leave();
    run_id_.clear();
    log_->error("RUN_CONFIG: rejected run '{}': {}", msg.run_id, e.what());
    detail_ = e.what();
    state_ = process_status_t::WAITING;
    process_status_t st{};
    st.run_id = msg.run_id;
    st.step = -1;
    st.process = process_;
    st.pid = static_cast<int32_t>(getpid());
    st.beat = beat_++;
    st.state = process_status_t::FAILED;
    st.config_digest = msg.digest;  // the configuration refused
    st.counts_config = 0;
    st.detail = detail_.substr(0, static_cast<std::size_t>(protocol().limits.text_bytes));
    st.n_channels = 0;  // nothing published in that run
    st.n_takes = 0;
    st.host = copies_.self().host;
    st.started = copies_.self().started;
    st.n_copies = 0;
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
  if (msg.config_digest != run_msg_.digest)  // said for another request of this run id (a recording's, an old one's)
    return Turn::refuse("a command for another request of run '" + msg.run_id + "' than the one this process took");
  onControl(envelope);
  if (msg.command == run_control_t::START) {
    if (state_ != process_status_t::READY) return Turn::take();  // already started: idempotent
    setState(process_status_t::RUNNING);
    if (restored_step_ < 0) onStart();  // a process gone on from a snapshot had started before it
    edge_.retry();  // messages that came before START
  } else {
    takeStop();
  }
  return Turn::take();
}

void NodeBase::takeStop() {
  stop_received_ = true;  // the run is over: its snapshot goes with it
  if (readyToLeave()) return leaveRun();
  if (!stop_pending_) stop_deadline_ = Clock::now() + milliseconds(protocol().stop_grace_ms);
  stop_pending_ = true;
}

Turn NodeBase::onStatus(const process_status_t& st) {
  if (st.process == process_) {  // our own, or a copy of this process's
    if (st.pid != getpid() || st.host != copies_.self().host) onCopy(st);
    return Turn::take();
  }
  edge_.claim(st);
  onPeerStatus(st);
  // A process that has just (re)joined our run catches up from what we say we published (the runner's beat
  // names the run too: it is not a process that joins it).
  const bool joined = !run_id_.empty() && st.run_id == run_id_ && st.config_digest == run_msg_.digest && st.step == -1 &&
                      (st.state == process_status_t::READY || st.state == process_status_t::RUNNING) &&
                      isProcessName(st.process);
  if (joined && edge_.publishedAny() && Clock::now() - announced_at_ >= milliseconds(protocol().idle_announce_ms))
    publishStatus();
  return Turn::take();
}

void NodeBase::onCopy(const process_status_t& st) {
  if (!copies_.refusal().empty()) return;  // refused already: leaving
  switch (copies_.heard(st, Clock::now(), protocol().limits.peers, copies_forgotten_)) {
    case Copies::Heard::Nothing:
      return;
    case Copies::Heard::New:
      // Said once for each copy, a few in all (the table of copies is bounded by protocol.limits.peers).
      if (++copies_said_ <= 5)
        log_->warn("another copy of {} on this bus: {}; this one is {}", process_, copies_.describe(Instance::of(st)),
                   copies_.self().text());
      publishStatus();  // named at once: the copy learns it is heard, and the later of the two refuses
      return;
    case Copies::Heard::Refuse:
      log_->error("{}", copies_.refusal());
      publishStatus();  // says FAILED, in no run, naming the earlier copy: it stops naming this one
      requestStop();
      return;
  }
}

void NodeBase::leaveRun() {
  if (state_ == process_status_t::WAITING) return;
  // Leaving without the run's STOP (SIGINT, SIGTERM): a snapshot of where it stands, to go on from it.
  if (!stop_received_ && state_ == process_status_t::RUNNING) maybeSnapshot(/*now=*/true);
  settleSnapshot(/*wait=*/true);
  if (stop_received_) removeSnapshot();
  try {
    onStop();
  } catch (const std::exception& e) {
    log_->error("leaving run '{}': {}", run_id_, e.what());
    detail_ = e.what();
  }
  log_->info("left run '{}' at step {} (it waits {:.2f} ms for an input, usually)", run_id_, last_step_,
             std::chrono::duration<double, std::milli>(edge_.usualWait()).count());
  // Left without the run's STOP (SIGINT, SIGTERM): the run goes on, and this process may be started again
  // into it. Its counts are not said as final (its peers would drop what the restarted one publishes next).
  const bool run_goes_on = !stop_received_;
  stop_received_ = false;
  stop_pending_ = false;
  edge_.leave();
  if (run_goes_on) edge_.forgetPublished();
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
  log_->log(failures_said_by_runner_ ? spdlog::level::debug : spdlog::level::err, "run '{}' failed here: {}", run_id_,
            why);
  edge_.suspend();
  setState(process_status_t::FAILED, why);
}

void NodeBase::publishStatus() {
  const auto now = Clock::now();
  const std::size_t text = static_cast<std::size_t>(protocol().limits.text_bytes);
  // A copy that refuses to serve says so, in no run, and claims no counts (its peers would take them as final).
  const bool refused = !copies_.refusal().empty();
  process_status_t st{};
  st.run_id = refused ? "" : run_id_;
  st.step = refused ? -1 : last_step_;
  st.process = process_;
  st.pid = static_cast<int32_t>(getpid());
  st.beat = beat_++;
  st.state = refused ? process_status_t::FAILED : state_;
  st.config_digest = st.run_id.empty() ? 0 : run_msg_.digest;
  st.detail = (refused ? copies_.refusal() : detail_).substr(0, text);
  // In a run of a phase it takes no part in (the planner in an intrinsic run): what is true of it.
  const std::vector<std::string> part = runProcesses(config_.phase, /*recorded=*/true);
  if (st.detail.empty() && !st.run_id.empty() && std::find(part.begin(), part.end(), process_) == part.end())
    st.detail = "idle in this run: its " + std::string(nameOf(kPhaseNames, config_.phase)) + " phase needs no " + process_;
  if (state_ == process_status_t::RUNNING && !refused) st.stuck = edge_.stuck().substr(0, text);
  st.counts_run = refused ? "" : edge_.historyRun();
  st.counts_config = refused ? 0 : edge_.historyConfig();
  if (!refused)
    for (const EdgeOutbound::Count& c : edge_.counts()) {
      st.channels.push_back(c.channel);
      st.counts.push_back(c.published);
      st.held_from.push_back(c.held_from);
    }
  st.n_channels = static_cast<int32_t>(st.channels.size());
  st.n_takes = 0;
  if (!st.run_id.empty()) restartPositions(st);
  st.host = copies_.self().host;
  st.started = copies_.self().started;
  st.copies = copies_.named(now, 3 * milliseconds(protocol().heartbeat_ms));
  st.n_copies = static_cast<int32_t>(st.copies.size());
  edge_.send(ch::status, st);
  next_beat_ = now + milliseconds(protocol().heartbeat_ms);
  announced_at_ = now;
}

void NodeBase::tick() {
  const auto now = Clock::now();
  if (now >= next_beat_) publishStatus();
  const bool in_run = state_ == process_status_t::RUNNING || state_ == process_status_t::DONE;
  if (in_run && announcesIdle()) {
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
  maybeSnapshot();
  if (stop_pending_) {
    // The grace runs while nothing comes: a message taken (a catching up goes on), or the process held up
    // (SIGSTOP, a suspended machine: it could take nothing meanwhile), starts it again.
    const auto grace = milliseconds(protocol().stop_grace_ms);
    stop_deadline_ = std::max(stop_deadline_, edge_.lastActivity() + grace);
    if (now - last_tick_ > milliseconds(protocol().heartbeat_ms)) stop_deadline_ = std::max(stop_deadline_, now + grace);
    if (readyToLeave() || now > stop_deadline_) {
      if (!readyToLeave()) onLeaveTimeout();
      leaveRun();
    }
  }
  last_tick_ = now;
}

auto NodeBase::idleAnnounceAfter() const -> Clock::duration {
  const Clock::duration least = milliseconds(protocol().idle_announce_ms);
  return std::min<Clock::duration>(std::max(least, edge_.usualWait() * protocol().idle_announce_pace),
                                   std::max<Clock::duration>(least, milliseconds(protocol().heartbeat_ms)));
}

int NodeBase::msUntilDue() const {
  const auto now = Clock::now();
  Clock::time_point due = std::min(next_beat_, edge_.nextDue());
  if ((state_ == process_status_t::RUNNING || state_ == process_status_t::DONE) && announcesIdle()) {
    const auto idle = idleAnnounceAfter();
    due = std::min(due, std::max(edge_.lastActivity() + idle, announced_at_ + std::max<Clock::duration>(announce_wait_, idle)));
  }
  if (stop_pending_) due = std::min(due, stop_deadline_);
  const auto ms = std::chrono::duration_cast<milliseconds>(due - now).count();
  return static_cast<int>(std::clamp<long long>(ms, 1, 100));
}

// ---- snapshots ------------------------------------------------------------------------

std::string NodeBase::snapshotPath(const std::string& run_id) const {
  if (snapshot_root_.empty() || run_id.empty()) return "";
  return (std::filesystem::path(snapshot_root_) / run_id / (process_ + ".snapshot")).string();
}

void NodeBase::restartPositions(process_status_t& st) const {
  for (const std::string& channel : edge_.ordered()) {
    std::int64_t from = 0;
    for (const EdgeInbound::Position& p : snapshot_at_)
      if (p.channel == channel) from = p.next;
    st.takes.push_back(channel);
    st.takes_from.push_back(from);
  }
  st.n_takes = static_cast<int32_t>(st.takes.size());
}

void NodeBase::settleSnapshot(bool wait) {
  std::string error;  // why it is not in place ("": it is)
  if (durable_child_) {
    if (!durable_child_->ended(wait)) return;
    error = durable_child_->error();
    durable_child_.reset();
  } else if (durable_.valid()) {
    if (!wait && durable_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
    try {
      durable_.get();
    } catch (const std::exception& e) {
      error = e.what();
    }
    durable_writer_.reset();
  } else {
    return;
  }
  if (!error.empty()) {
    // The run goes on: the earlier snapshot stays, and peers hold what followed it.
    log_->error("{}: the earlier snapshot stays", error);
    return;
  }
  snapshot_at_ = std::move(durable_at_);
  ++snapshots_taken_;
  log_->debug("snapshot of step {} in place", durable_step_);
  if (!run_id_.empty()) publishStatus();  // its peers may let go of what came before it
}

void NodeBase::writeSnapshot(SnapshotWriter& w) {
  w.section("run");
  w.str(run_id_);
  w.str(process_);
  w.i64(run_msg_.digest);
  w.i64(last_step_);
  edge_.save(w);
  w.section(process_.c_str());
  saveState(w);
  w.finish();
}

void NodeBase::maybeSnapshot(bool now) {
  settleSnapshot(/*wait=*/now);
  if (durable_child_ || durable_.valid()) return;  // the last one is not in place yet
  const int every = config_.protocol.recovery.snapshot_steps;
  if (snapshot_root_.empty() || run_id_.empty() || state_ != process_status_t::RUNNING ||
      !learning(config_.phase) || every <= 0 || !snapshots() || edge_.failed())
    return;
  if ((!now && last_step_ < next_snapshot_) || last_step_ < 0 || !atRest()) return;
  // The run's last steps are handled (the goals phase looks once more at step run.steps): nothing is left to go on
  // from, and the run's STOP removes its snapshots.
  if (!now && last_step_ >= config_.steps) return;
  const std::string path = snapshotPath(run_id_);
  try {
    const auto began = Clock::now();
    prepareSnapshot();
    durable_at_ = edge_.positions();
    durable_step_ = last_step_;
    if (fork_snapshots_) {
      // The copy writes, flushes and renames; this process goes on at once.
      durable_child_ = std::make_unique<SnapshotChild>([this, &path] {
        SnapshotWriter w(path);
        writeSnapshot(w);
        w.commit();
      });
    } else {
      // Written here, flushed and renamed on a thread of its own.
      auto w = std::make_unique<SnapshotWriter>(path);
      writeSnapshot(*w);
      durable_writer_ = std::move(w);
      durable_ = std::async(std::launch::async, [writer = durable_writer_.get()] { writer->commit(); });
    }
    log_->debug("snapshot of step {} begun ({}) in {} ms: {}", last_step_, fork_snapshots_ ? "forked" : "written",
                std::chrono::duration_cast<milliseconds>(Clock::now() - began).count(), path);
    if (now) settleSnapshot(/*wait=*/true);
  } catch (const std::exception& e) {
    // The run goes on: the earlier snapshot stays, and peers hold what followed it.
    log_->error("{}: the earlier snapshot stays", e.what());
  }
  next_snapshot_ = (last_step_ / every + 1) * every;
}

void NodeBase::restoreSnapshot() {
  restored_step_ = -1;
  snapshot_at_.clear();
  snapshots_taken_ = 0;
  const int every = config_.protocol.recovery.snapshot_steps;
  next_snapshot_ = every;
  const std::string path = snapshotPath(run_id_);
  std::error_code ec;
  if (path.empty() || !learning(config_.phase) || every <= 0 || !snapshots() ||
      !std::filesystem::exists(path, ec))
    return;
  try {
    SnapshotReader r(path, static_cast<std::uint64_t>(config_.protocol.recovery.snapshot_mb) << 20);
    r.section("run");
    if (r.str("run id", 256) != run_id_) r.refuse("run id", "a snapshot of another run");
    if (r.str("process", 64) != process_) r.refuse("process", "a snapshot of another process");
    if (r.i64("configuration digest") != run_msg_.digest)
      r.refuse("configuration digest", "a snapshot of another configuration of run '" + run_id_ + "'");
    const std::int64_t step = r.within("step", 0, std::max<std::int64_t>(0, config_.steps - 1));
    edge_.load(r);
    r.section(process_.c_str());
    loadState(r);
    r.end();
    last_step_ = restored_step_ = step;
    snapshot_at_ = edge_.positions();
    next_snapshot_ = (step / every + 1) * every;
    log_->info("goes on from its snapshot of step {} ({})", step, path);
  } catch (const std::exception& e) {
    // A state read in part is no state: the run is taken from its start (its peers may no longer hold it: then
    // the edge says so, naming the channel).
    log_->error("{}: the run is taken from its start", e.what());
    edge_.join(run_id_, &config_, requestOf(run_msg_));
    for (const auto& clear : joins_) clear();
    onConfigured(config_);
    last_step_ = -1;
  }
}

void NodeBase::removeSnapshot() {
  const std::string path = snapshotPath(run_id_);
  // Only a snapshot of this request: one this process took or went on from (another request of the run id, a
  // recording's taken by mistake, leaves the file of the request that wrote it).
  if (path.empty() || (snapshots_taken_ == 0 && restored_step_ < 0)) return;
  std::error_code ec;
  std::filesystem::remove(path, ec);
  std::filesystem::remove(path + ".tmp", ec);
  std::filesystem::remove(std::filesystem::path(path).parent_path(), ec);  // only if nothing else is there
}

}  // namespace afford
