// What every process shares (docs/processes-and-channels.md): the
// message edge (afford/edge.hpp) and the run lifecycle
//   WAITING --RUN_CONFIG--> READY --START--> RUNNING [--> DONE] --STOP--> WAITING
// with FAILED when a handler throws, a bound is reached, or the run's
// configuration is refused (the reason in STATUS detail; the process stays
// alive and serves the next run). STATUS goes out on every change of state,
// every protocol.heartbeat_ms, and as soon as the process has been idle in a
// run for protocol.idle_announce_ms (doubling while it stays idle): it carries
// the counts of what the process published, so a receiver that lost the last
// of them asks for it within milliseconds.
//
// Channels in:  RUN_CONFIG, RUN_CONTROL, STATUS, RESEND (+ what the process subscribes)
// Channels out: STATUS, RESEND (+ what the process publishes)
#pragma once
#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include <chrono>
#include <functional>
#include <future>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "afford/config.hpp"
#include "afford/edge.hpp"
#include "afford/process_status_t.hpp"
#include "afford/run_config_t.hpp"
#include "afford/run_control_t.hpp"

namespace afford {

// A message that a handler finds impossible only by working on it (a scene
// that does not decode): thrown before the handler changes anything, it is
// refused as a rule's refusal is.
struct Refusal : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// What a node takes from one channel, and when: its input rule. A node states
// each of its inputs once, in words (`rule`, what `afford processes --rules`
// prints) and as clauses, which NodeBase tries in order on every message of
// the channel (and again whenever another message is taken):
//   ignoreIf(test)  the message is taken and nothing is done with it;
//   refuse(why)     it cannot be the channel's next message: refused with the
//                   reason (the edge expects that serial again);
//   waitFor(ready)  it is not its turn: kept until it is (Turn::later);
// and when every clause passes, the handler (`then`) gets it. Clauses and
// handler may hold for one phase only (`in(phase)`); in a phase with none, the
// channel's messages are taken and ignored. Handlers hold no ordering code.
template <class Msg>
class Input {
 public:
  using Test = std::function<bool(const Msg&)>;
  using Why = std::function<std::string(const Msg&)>;
  using Handler = std::function<void(const Msg&, const Envelope&)>;

  explicit Input(std::string rule) : rule_(std::move(rule)) {}
  // What follows applies in this phase only (until the next in()).
  Input& in(Phase phase) { return in({phase}); }
  // ... in these phases (the same clauses for each).
  Input& in(std::initializer_list<Phase> phases) {
    phases_.clear();
    for (Phase p : phases) phases_.push_back(static_cast<int>(p));
    for (int p : this->phases()) sections_[p].defined = true;
    return *this;
  }
  Input& ignoreIf(Test test) { return add({Clause::Ignore, std::move(test), {}}); }
  Input& refuse(Why why) { return add({Clause::Refuse, {}, std::move(why)}); }
  Input& waitFor(Test ready) { return add({Clause::Wait, std::move(ready), {}}); }
  // Keys in order, from next(): a smaller one is refused ("<what> k is in the past (the next is n)"),
  // a larger one waits.
  Input& inOrder(std::function<std::int64_t(const Msg&)> key, std::function<std::int64_t()> next, std::string what) {
    refuse([key, next, what](const Msg& m) {
      const std::int64_t k = key(m), n = next();
      return k < n ? what + " " + std::to_string(k) + " is in the past (the next is " + std::to_string(n) + ")"
                   : std::string();
    });
    return waitFor([key, next](const Msg& m) { return key(m) == next(); });
  }
  // Steps in order, from next().
  Input& stepInOrder(std::function<std::int64_t()> next) {
    return inOrder([](const Msg& m) { return m.step; }, std::move(next), "step");
  }
  // A step of the run: below `steps()`.
  Input& withinRun(std::function<std::int64_t()> steps) {
    return refuse([steps](const Msg& m) {
      return m.step >= steps() ? "step " + std::to_string(m.step) + " is beyond the run's last step" : std::string();
    });
  }
  Input& then(std::function<void(const Msg&)> handler) {
    return then(Handler([h = std::move(handler)](const Msg& m, const Envelope&) { h(m); }));
  }
  Input& then(Handler handler) {
    for (int p : phases()) {
      sections_[p].handler = handler;
      sections_[p].defined = true;
    }
    return *this;
  }
  const std::string& rule() const { return rule_; }

  // The message's turn, by the clauses of the run's phase; on Take, it has been handled.
  Turn offer(const Msg& m, const Envelope& e, Phase phase) const {
    const Section& s = sections_[static_cast<int>(phase)];
    if (!s.defined) return Turn::take();  // not an input in this phase
    for (const Clause& c : s.clauses) {
      switch (c.kind) {
        case Clause::Ignore:
          if (c.test(m)) return Turn::take();
          break;
        case Clause::Refuse:
          if (std::string why = c.why(m); !why.empty()) return Turn::refuse(std::move(why));
          break;
        case Clause::Wait:
          if (!c.test(m)) return Turn::later();
          break;
      }
    }
    if (s.handler) {
      try {
        s.handler(m, e);
      } catch (const Refusal& r) {
        return Turn::refuse(r.what());
      }
    }
    return Turn::take();
  }

 private:
  struct Clause {
    enum Kind { Ignore, Refuse, Wait } kind;
    Test test;
    Why why;
  };
  struct Section {
    std::vector<Clause> clauses;
    Handler handler;
    bool defined = false;
  };
  std::vector<int> phases() const {
    if (!phases_.empty()) return phases_;
    std::vector<int> all;
    for (std::size_t p = 0; p < kPhases; ++p) all.push_back(static_cast<int>(p));
    return all;
  }
  Input& add(Clause c) {
    for (int p : phases()) {
      sections_[p].clauses.push_back(c);
      sections_[p].defined = true;
    }
    return *this;
  }

  std::string rule_;
  Section sections_[kPhases];  // by Phase
  std::vector<int> phases_;    // the phases of what is being added (empty: every phase)
};

// Two inputs that make one thing together, whichever comes first (the
// planner's object: the FOCUS that shows it and the PREDICTION of its
// affordances). Each input's handler gives its part (first(), second()); once
// both are held, the join's handler gets them, once. The node says when a new
// pair begins (clear(); NodeBase clears every join at each RUN_CONFIG), and its
// inputs' clauses may ask what is held (a second part of one pair is refused or
// waits by the input's own clauses).
template <class A, class B>
class Both {
 public:
  using Handler = std::function<void(const A&, const B&)>;
  explicit Both(Handler handler) : handler_(std::move(handler)) {}
  void first(const A& a) {
    a_ = a;
    fire();
  }
  void second(const B& b) {
    b_ = b;
    fire();
  }
  bool hasFirst() const { return a_.has_value(); }
  bool hasSecond() const { return b_.has_value(); }
  void clear() {
    a_.reset();
    b_.reset();
  }

 private:
  void fire() {
    if (a_ && b_) handler_(*a_, *b_);
  }
  Handler handler_;
  std::optional<A> a_;
  std::optional<B> b_;
};

class NodeBase {
 public:
  // `protocol`: what the process uses between runs (the config folder's defaults).
  NodeBase(lcm::LCM& lcm, std::string process, std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol);
  virtual ~NodeBase() = default;
  NodeBase(const NodeBase&) = delete;
  NodeBase& operator=(const NodeBase&) = delete;

  // Heartbeat, idle announcement, request retries, a pending STOP (call from
  // the loop after every handle; wall clock only here).
  void tick();
  // Milliseconds until tick() has something to do by itself.
  int msUntilDue() const;
  const std::string& process() const { return process_; }
  const std::string& runId() const { return run_id_; }
  int8_t state() const { return state_; }
  // The run channels this process takes, in serial order (what it subscribes to).
  const std::vector<std::string>& takes() const { return edge_.ordered(); }
  std::int64_t lastStep() const { return last_step_; }  // the last step handled in the run (-1: none)
  // Leave the run (used on STOP and at shutdown); subclasses flush in onStop().
  void leaveRun();
  // Each input's channel and rule, in the order the node states them.
  struct InputRule {
    std::string channel, rule;
  };
  const std::vector<InputRule>& rules() const { return rules_; }
  // A keyed bus (afford/auth.hpp): set before the first message is handled.
  void useBusKey(std::shared_ptr<const BusKey> key) { edge_.useKey(std::move(key)); }
  // Fed a recording (replay, explain): nothing it publishes is held, as no peer can ask for it.
  void holdNothingPublished() { edge_.holdNothingPublished(); }
  // Snapshots (docs/processes-and-channels.md, "Runs of any length"): a node
  // that says it takes them (snapshots()) saves its state, with the edge's
  // positions and what it published, every protocol.recovery.snapshot_steps
  // steps of an intrinsic run, between two messages, as
  // <folder>/<run-id>/<process>.snapshot; restarted into the same run (same
  // configuration), it loads it and takes each channel again from where the
  // snapshot was taken. The run's end (STOP) removes it. "" (the default): none.
  void keepSnapshotsIn(std::string folder) { snapshot_root_ = std::move(folder); }
  // Written by a forked copy of the process (SnapshotChild), which goes on at once; off (the default): written
  // on its own path and flushed on a thread. Only a process whose every component is C++ forks: a copy of a
  // Python interpreter cannot run Python safely.
  void forkSnapshots(bool on) { fork_snapshots_ = on; }
  // Its run's failure is said by the runner that drives the run, in the same output (memq: which process failed,
  // and why): said here at debug level only, so that it is said once. Off (the default): said here, as an error.
  void leaveFailuresToRunner(bool on) { failures_said_by_runner_ = on; }
  std::string snapshotPath(const std::string& run_id) const;
  // The step of the snapshot this process went on from in its run (-1: none).
  std::int64_t restoredStep() const { return restored_step_; }
  std::int64_t snapshotsTaken() const { return snapshots_taken_; }
  const EdgeDrops& drops() const { return edge_.drops(); }
  // Why this process refuses to serve: an earlier copy of it on the bus names it (afford/edge_peers.hpp,
  // Copies). It has said so (a STATUS saying FAILED) and asked to stop (requestStop()); "" while it serves.
  const std::string& refusal() const { return copies_.refusal(); }

 protected:
  // An input of the node (see Input): a channel of the run, taken in serial
  // order, by the rule stated here in words and built on the returned Input.
  // Nothing is taken before START; after each message taken, afterInput().
  template <class Msg>
  Input<Msg>& takes(const Channel<Msg>& channel, std::string rule) {
    auto input = std::make_shared<Input<Msg>>(std::move(rule));
    rules_.push_back({channel.name, input->rule()});
    edge_.subscribe(
        channel,
        [this, input](const Msg& m, const Envelope& e) {
          if (state_ == process_status_t::READY) return Turn::later();  // its turn comes after START
          const Turn t = input->offer(m, e, config_.phase);
          if (t.kind() == Turn::Kind::Take) afterInput();
          return t;
        },
        Scope::Run, Order::Serial);
    return *input;
  }
  // A join of two of the node's inputs (see Both, a member of the node),
  // stated in words beside the inputs' rules (`afford processes --rules`) as
  // the two channels joined.
  template <class A, class B>
  void joins(Both<A, B>& join, const Channel<A>& first, const Channel<B>& second, std::string rule) {
    rules_.push_back({std::string(first.name) + " + " + second.name, std::move(rule)});
    joins_.push_back([&join] { join.clear(); });
  }
  // Called after every message an input took: where what follows from the
  // node's inputs together happens (the eye starts a step there).
  virtual void afterInput() {}
  // Publish on a channel of the run (serial, digest, history for RESEND).
  template <class Msg>
  void publish(const Channel<Msg>& channel, Msg msg) {
    edge_.publish(channel, msg);
  }
  void handled(int64_t step) { last_step_ = std::max(last_step_, step); }
  void setState(int8_t state, const std::string& detail = "");
  // The run fails here: FAILED with the reason; the process stays in the run until STOP.
  void failRun(const std::string& why);
  const RunConfig& config() const { return config_; }
  const run_config_t& runConfigMessage() const { return run_msg_; }
  Edge& edge() { return edge_; }
  const Edge& edge() const { return edge_; }

  // On STOP, leave only once this says so (or after protocol.stop_grace_ms in which no message of the run was
  // taken and the process was not held up, e.g. paused).
  virtual bool readyToLeave() { return true; }
  // Announce its STATUS when idle in a run (see the file comment): a node that published something, whose
  // counts a receiver may lack. (The logger, once its log holds the run's end: what its log holds.)
  virtual bool announcesIdle() const { return edge_.publishedAny(); }
  // The run's STOP, as if it had come: for a node that learns otherwise that its run was stopped (the logger,
  // from its peers' final counts, when the STOP did not reach it).
  void takeStop();
  bool stopTaken() const { return stop_received_; }  // the run's STOP came (or takeStop())
  virtual void onLeaveTimeout() {}
  // Take part in this run? (The logger records only runs with run.record.)
  virtual bool wantsRun(const RunConfig&) { return true; }
  // Build the core for a run; throw ConfigError to refuse the configuration.
  virtual void onConfigured(const RunConfig& config) = 0;
  virtual void onStart() {}
  virtual void onStop() {}
  // The bytes of the run's RUN_CONFIG and RUN_CONTROL messages (the logger records them).
  virtual void onControl(const Envelope&) {}
  // A STATUS of another process (the logger keeps its manifest from them).
  virtual void onPeerStatus(const process_status_t&) {}
  // Snapshots: does this node take them (in this run)? Can it now (nothing of a step in flight elsewhere, e.g.
  // on a worker thread)? Its state, written and read back in the same order (SnapshotReader refuses a file
  // out of step, naming the field).
  virtual bool snapshots() const { return false; }
  virtual bool atRest() const { return true; }
  // Before saveState, on the process's own path: whatever its state waits for on another thread done (saveState
  // may run in a forked copy of the process, which holds only the calling thread).
  virtual void prepareSnapshot() {}
  virtual void saveState(SnapshotWriter&) {}
  virtual void loadState(SnapshotReader&) {}
  // Where a restart would take each channel again, as STATUS says it (takes, takes_from): the latest
  // snapshot's positions (0 without one). The logger says what its log holds.
  virtual void restartPositions(process_status_t& st) const;

  lcm::LCM& lcm_;
  std::shared_ptr<spdlog::logger> log_;

 private:
  using Clock = std::chrono::steady_clock;
  Turn onRunConfig(const run_config_t& msg, const Envelope& envelope);
  Turn onRunControl(const run_control_t& msg, const Envelope& envelope);
  Turn onStatus(const process_status_t& msg);
  void onCopy(const process_status_t& msg);  // a STATUS of this process's name from another pid or host
  void publishStatus();
  const ProtocolConfig& protocol() const { return edge_.protocol(); }

  std::string process_;
  Edge edge_;
  std::string run_id_;
  run_config_t run_msg_;  // the run's RUN_CONFIG (its digest is in every STATUS)
  RunConfig config_;
  int8_t state_ = process_status_t::WAITING;
  std::string detail_;
  int64_t last_step_ = -1;
  std::int64_t beat_ = 0;  // STATUS messages published so far
  Copies copies_;          // the other copies of this process heard on the bus; who this one is
  std::int64_t copies_said_ = 0;  // copies said in the log (the first few)
  std::int64_t copies_forgotten_ = 0;  // copies forgotten beyond protocol.limits.peers
  Clock::time_point next_beat_{};
  // Idle announcement: after protocol.idle_announce_ms, or idle_announce_pace times the usual wait for an
  // input if longer (never longer than the heartbeat).
  Clock::duration idleAnnounceAfter() const;
  // When the last one went out, and how long until the next.
  Clock::time_point announced_at_{};
  Clock::duration announce_wait_{};
  bool stop_pending_ = false;
  Clock::time_point stop_deadline_{};
  Clock::time_point last_tick_{};  // a longer gap between two ticks than a heartbeat: the process was held up
  std::vector<InputRule> rules_;
  std::vector<std::function<void()>> joins_;  // clearing each join (at each RUN_CONFIG)
  // Snapshots.
  void maybeSnapshot(bool now = false);  // now: whatever the step (leaving the run without its STOP)
  // The snapshot being made durable (written by a forked copy, or flushed and renamed on a thread of its own):
  // when it is, its positions become what STATUS says. wait: until it is (leaving the run).
  void settleSnapshot(bool wait);
  void writeSnapshot(SnapshotWriter& w);  // everything but the flush
  void restoreSnapshot();
  void removeSnapshot();
  std::string snapshot_root_;
  std::int64_t next_snapshot_ = 0;  // the step after which the next one is taken
  std::vector<EdgeInbound::Position> snapshot_at_;  // the latest one's positions (what STATUS says)
  std::int64_t restored_step_ = -1;
  std::int64_t snapshots_taken_ = 0;
  bool stop_received_ = false;
  bool fork_snapshots_ = false;
  bool failures_said_by_runner_ = false;
  std::unique_ptr<SnapshotWriter> durable_writer_;  // declared before durable_: the task ends before it goes
  std::vector<EdgeInbound::Position> durable_at_;
  std::int64_t durable_step_ = -1;
  std::future<void> durable_;
  std::unique_ptr<SnapshotChild> durable_child_;
};

}  // namespace afford
