// The LCM edge shared by every process (ARCHITECTURE.md "How a process is
// built"): decoding with fingerprint checks, one-line drops naming the channel
// and reason, the run lifecycle (RUN_CONFIG -> READY -> START -> RUNNING ->
// STOP) and the STATUS heartbeat.
//
// Channels in:  RUN_CONFIG, RUN_CONTROL (+ whatever the process subscribes)
// Channels out: STATUS
#pragma once
#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "afford/checks.hpp"
#include "afford/config.hpp"
#include "afford/process_status_t.hpp"
#include "afford/run_config_t.hpp"
#include "afford/run_control_t.hpp"

namespace afford {

// Decode an LCM buffer as Msg; on failure return false with a reason.
template <class Msg>
bool decodeAtEdge(const lcm::ReceiveBuffer* rbuf, Msg& out, std::string& reason) {
  if (rbuf->data_size < 8) {
    reason = "message of " + std::to_string(rbuf->data_size) + " bytes is shorter than a fingerprint";
    return false;
  }
  int64_t hash = 0;
  __int64_t_decode_array(rbuf->data, 0, 8, &hash, 1);
  if (hash != Msg::getHash()) {
    reason = std::string("wrong fingerprint: not an afford.") + Msg::getTypeName();
    return false;
  }
  try {
    const int n = out.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size));
    if (n < 0) {
      reason = std::string("malformed afford.") + Msg::getTypeName() + " (truncated or negative array size)";
      return false;
    }
    if (static_cast<uint32_t>(n) != rbuf->data_size) {
      reason = std::to_string(rbuf->data_size - n) + " trailing bytes after the message";
      return false;
    }
  } catch (const std::exception& e) {
    reason = std::string("malformed afford.") + Msg::getTypeName() + ": " + e.what();
    return false;
  }
  return true;
}


template <class Msg, class = void>
inline constexpr bool kHasCheck = false;
template <class Msg>
inline constexpr bool kHasCheck<Msg, std::void_t<decltype(checkMessage(std::declval<const Msg&>(), std::declval<const RunConfig&>()))>> = true;

class NodeBase {
 public:
  NodeBase(lcm::LCM& lcm, std::string process, std::shared_ptr<spdlog::logger> log);
  virtual ~NodeBase() = default;
  NodeBase(const NodeBase&) = delete;
  NodeBase& operator=(const NodeBase&) = delete;

  // Publish the heartbeat when due (call from the loop; wall clock only here).
  void tick();
  const std::string& process() const { return process_; }
  const std::string& runId() const { return run_id_; }
  int8_t state() const { return state_; }
  // Leave the run (used on STOP and at shutdown); subclasses flush in onStop().
  void leaveRun();

 protected:
  // Subscribe to a typed channel. The handler sees only messages that decoded,
  // belong to the run, and pass checkMessage() for their type.
  template <class Msg>
  void subscribe(const std::string& channel, std::function<void(const Msg&)> handler, int queue = 10000) {
    auto holder = std::make_unique<Holder>();
    holder->fn = [this, channel, handler](const lcm::ReceiveBuffer* rbuf, const std::string&) {
      Msg msg;
      std::string reason;
      if (!decodeAtEdge(rbuf, msg, reason)) return drop(channel, reason);
      if (!acceptRun(channel, msg.run_id)) return;
      if constexpr (kHasCheck<Msg>) {
        if (const std::string why = checkMessage(msg, config_); !why.empty()) return drop(channel, why);
      }
      handler(msg);
    };
    lcm::Subscription* s = lcm_.subscribe(channel, &Holder::on, holder.get());
    s->setQueueCapacity(queue);
    holders_.push_back(std::move(holder));
  }
  // Raw subscription (logger): no decoding, no run check.
  void subscribeRaw(const std::string& channel_regex,
                    std::function<void(const lcm::ReceiveBuffer*, const std::string&)> handler, int queue = 10000);

  void drop(const std::string& channel, const std::string& reason);
  void handled(int64_t step) { last_step_ = std::max(last_step_, step); }
  void setState(int8_t state, const std::string& detail = "");
  const RunConfig& config() const { return config_; }
  const run_config_t& runConfigMessage() const { return run_msg_; }

  template <class Msg>
  void publish(const std::string& channel, const Msg& msg) {
    lcm_.publish(channel, &msg);
  }

  // Build the core for a run; throw ConfigError to refuse the configuration.
  virtual void onConfigured(const RunConfig& config) = 0;
  virtual void onStart() {}
  virtual void onStop() {}

  lcm::LCM& lcm_;
  std::shared_ptr<spdlog::logger> log_;

 private:
  struct Holder {
    std::function<void(const lcm::ReceiveBuffer*, const std::string&)> fn;
    void on(const lcm::ReceiveBuffer* rbuf, const std::string& channel) { fn(rbuf, channel); }
  };
  bool acceptRun(const std::string& channel, const std::string& run_id);
  void onRunConfig(const lcm::ReceiveBuffer* rbuf);
  void onRunControl(const lcm::ReceiveBuffer* rbuf);
  void publishStatus();

  std::string process_;
  std::vector<std::unique_ptr<Holder>> holders_;
  std::string run_id_;
  run_config_t run_msg_;
  RunConfig config_;
  int8_t state_ = process_status_t::WAITING;
  std::string detail_;
  int64_t last_step_ = -1;
  std::chrono::steady_clock::time_point next_beat_{};
};

// The main() of every process: flags (--lcm-url, --log-level, plus extras),
// the node, the loop on handleTimeout until SIGINT/SIGTERM, orderly shutdown.
struct ProcessSpec {
  std::string name;         // "eye"
  std::string description;  // one line for --help
};
int processMain(int argc, char** argv, const ProcessSpec& spec,
                const std::function<void(class CLIHook&)>& add_options,
                const std::function<std::unique_ptr<NodeBase>(lcm::LCM&, std::shared_ptr<spdlog::logger>)>& make_node);

// Lets a process add its own flags to the shared command line.
class CLIHook {
 public:
  explicit CLIHook(void* app) : app_(app) {}
  void option(const std::string& name, std::string& target, const std::string& help);

 private:
  void* app_;
};

// Set by SIGINT/SIGTERM.
bool stopRequested();
void installStopHandlers();

}  // namespace afford
