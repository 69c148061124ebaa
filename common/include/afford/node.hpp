// What every process shares (ARCHITECTURE.md "How a process is built"): the
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
#include <memory>
#include <string>
#include <vector>

#include "afford/config.hpp"
#include "afford/edge.hpp"
#include "afford/process_status_t.hpp"
#include "afford/run_config_t.hpp"
#include "afford/run_control_t.hpp"

namespace afford {

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
  // A keyed bus (afford/auth.hpp): set before the first message is handled.
  void useBusKey(std::shared_ptr<const BusKey> key) { edge_.useKey(std::move(key)); }
  const EdgeDrops& drops() const { return edge_.drops(); }

 protected:
  // A channel of the run, in serial order; `handler` returns a Turn
  // (afford/edge.hpp): Take, Later (not its turn yet) or Refuse.
  template <class Msg, class F>
  void subscribe(const Channel<Msg>& channel, F handler) {
    edge_.subscribe(channel, std::move(handler), Scope::Run, Order::Serial);
  }
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

  // On STOP, leave only once this says so (or after protocol.stop_grace_ms).
  virtual bool readyToLeave() { return true; }
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

  lcm::LCM& lcm_;
  std::shared_ptr<spdlog::logger> log_;

 private:
  using Clock = std::chrono::steady_clock;
  Turn onRunConfig(const run_config_t& msg, const Envelope& envelope);
  Turn onRunControl(const run_control_t& msg, const Envelope& envelope);
  Turn onStatus(const process_status_t& msg);
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
  Clock::time_point next_beat_{};
  // Idle announcement: when the last one went out, and how long until the next.
  Clock::time_point announced_at_{};
  Clock::duration announce_wait_{};
  bool stop_pending_ = false;
  Clock::time_point stop_deadline_{};
};

// The main() of every process: flags (--lcm-url, --log-level, --config-dir,
// --bus-key, plus extras), the node, the loop on handleTimeout until
// SIGINT/SIGTERM, orderly shutdown.
struct ProcessSpec {
  std::string name;         // "eye"
  std::string description;  // one line for --help
};
class CLIHook;
int processMain(int argc, char** argv, const ProcessSpec& spec, const std::function<void(CLIHook&)>& add_options,
                const std::function<std::unique_ptr<NodeBase>(lcm::LCM&, std::shared_ptr<spdlog::logger>,
                                                              const ProtocolConfig&)>& make_node);

// Lets a process add its own flags to the shared command line.
class CLIHook {
 public:
  explicit CLIHook(void* app) : app_(app) {}
  void option(const std::string& name, std::string& target, const std::string& help);

 private:
  void* app_;
};

// The folder of defaults.yaml (--config-dir's default): the source tree's config/.
std::string defaultConfigDir();

// Large transient buffers (LCM's reassembly of fragmented messages) go back to
// the kernel when freed, so a flood of them does not stay resident.
void boundHeapGrowth();

// Set by SIGINT/SIGTERM.
bool stopRequested();
void installStopHandlers();

}  // namespace afford
