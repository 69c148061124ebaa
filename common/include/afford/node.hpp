// The LCM edge shared by every process (ARCHITECTURE.md "How a process is
// built"): decoding with fingerprint checks, one-line drops naming the channel
// and reason, the run lifecycle (RUN_CONFIG -> READY -> START -> RUNNING ->
// STOP), the STATUS heartbeat, and reliable delivery (afford/serials.hpp):
// each subscribed channel is taken in serial order without repeats, missing
// messages are asked for on RESEND, and the history of what this process
// published in the run answers others' requests. A handler that gets a
// message before its turn (another channel's message it depends on is late)
// calls defer(): the message is offered again after each message handled.
//
// Channels in:  RUN_CONFIG, RUN_CONTROL, STATUS, RESEND (+ what the process subscribes)
// Channels out: STATUS, RESEND (+ what the process publishes)
#pragma once
#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <map>
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
#include "afford/serials.hpp"

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

// Ask the publisher of r.channel for the serials r.first..r.last again (RESEND).
void publishResend(lcm::LCM& lcm, const std::string& run_id, const SerialTracker::Request& r,
                   const std::string& requester);

class NodeBase {
 public:
  NodeBase(lcm::LCM& lcm, std::string process, std::shared_ptr<spdlog::logger> log);
  virtual ~NodeBase();  // unsubscribes: the bus may outlive the node (a restart in one process)
  NodeBase(const NodeBase&) = delete;
  NodeBase& operator=(const NodeBase&) = delete;

  // Publish the heartbeat when due (call from the loop; wall clock only here).
  void tick();
  const std::string& process() const { return process_; }
  const std::string& runId() const { return run_id_; }
  int8_t state() const { return state_; }
  std::int64_t lastStep() const { return last_step_; }  // the last step handled in the run (-1: none)
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
      if (!inSerialOrder(channel, msg.serial)) return;
      dispatch(channel, [handler, msg]() { handler(msg); });
    };
    tracked_.push_back(channel);
    holder->sub = lcm_.subscribe(channel, &Holder::on, holder.get());
    holder->sub->setQueueCapacity(queue);
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

  // Publish with the channel's next serial, and keep the bytes in the run's
  // history (for RESEND).
  template <class Msg>
  void publish(const std::string& channel, const Msg& msg) {
    Msg out = msg;
    std::vector<std::vector<std::uint8_t>>& h = history_[channel];
    out.serial = static_cast<std::int64_t>(h.size());
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(out.getEncodedSize()));
    out.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    lcm_.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
    h.push_back(std::move(bytes));
  }
  // Called by a handler: this message came before its turn; offer it again later.
  void defer() { defer_now_ = true; }
  // For raw subscribers (the logger): take `channel` in serial order too.
  void trackChannel(const std::string& channel) { tracked_.push_back(channel); }
  void expectSerial(const std::string& channel, std::int64_t next) { serials_.expect(channel, next); }
  bool inSerialOrder(const std::string& channel, std::int64_t serial);
  std::int64_t missingMessages() const { return serials_.missing(); }
  // On STOP, leave only once this says so (or after `stop_grace` seconds):
  // the logger waits for the messages still missing from its log.
  virtual bool readyToLeave() { return true; }
  virtual void onLeaveTimeout() {}

  // Build the core for a run; throw ConfigError to refuse the configuration.
  virtual void onConfigured(const RunConfig& config) = 0;
  virtual void onStart() {}
  virtual void onStop() {}

  lcm::LCM& lcm_;
  std::shared_ptr<spdlog::logger> log_;

 private:
  struct Holder {
    std::function<void(const lcm::ReceiveBuffer*, const std::string&)> fn;
    lcm::Subscription* sub = nullptr;
    void on(const lcm::ReceiveBuffer* rbuf, const std::string& channel) { fn(rbuf, channel); }
  };
  bool acceptRun(const std::string& channel, const std::string& run_id);
  void onRunConfig(const lcm::ReceiveBuffer* rbuf);
  void onRunControl(const lcm::ReceiveBuffer* rbuf);
  void onStatus(const lcm::ReceiveBuffer* rbuf);
  void onResend(const lcm::ReceiveBuffer* rbuf);
  void publishStatus();
  void askMissing();
  void dispatch(const std::string& channel, std::function<void()> call);
  void retryDeferred();
  void forgetRun();

  std::string process_;
  std::vector<std::unique_ptr<Holder>> holders_;
  std::string run_id_;
  run_config_t run_msg_;
  RunConfig config_;
  int8_t state_ = process_status_t::WAITING;
  std::string detail_;
  int64_t last_step_ = -1;
  std::chrono::steady_clock::time_point next_beat_{};
  // Reliable delivery.
  std::vector<std::string> tracked_;  // subscribed channels
  SerialTracker serials_;
  std::map<std::string, std::vector<std::vector<std::uint8_t>>> history_;  // published, by channel
  std::string history_run_;  // the run of history_ (kept after STOP for late requests)
  struct Deferred {
    std::string channel;
    std::function<void()> call;
  };
  std::vector<Deferred> deferred_;
  bool defer_now_ = false, retrying_ = false;
  bool stop_pending_ = false;
  std::chrono::steady_clock::time_point stop_deadline_{};
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
