// The message edge: the one place where bytes from the bus become typed
// messages (docs/processes-and-channels.md, "The message edge"). Every
// subscriber goes through it: the processes (NodeBase), the runner, the
// viewer, `afford status` and replay. For each datagram, in this order:
//
//   0. tag: on a bus with a key (afford/auth.hpp), the last 32 bytes must be
//      the tag of the rest on this channel, else the message is dropped and
//      counted; the tag is taken off, and the steps below see the message;
//   1. fingerprint: the channel's type, else dropped;
//   2. run: the run id is read (bounded) before anything is decoded, and must
//      be a safe name (afford/names.hpp); a message of no run this subscriber
//      serves is dropped;
//   3. bounds: every string length and array size against the bytes left and
//      against a maximum from the configuration (afford/bounds.hpp), so LCM's
//      decoder never sees a size it could overflow or over-allocate on;
//   4. decode, then checkMessage(): every field (afford/checks.hpp); a type
//      without a check does not compile;
//   5. digest: the last 8 bytes must be the digest of the rest (afford/seal.hpp);
//   6. order: run messages are taken in serial order, once; a gap is asked
//      for at once (RESEND); a repeat is dropped quietly; the message at the
//      expected serial must name, in prev_digest, the digest of the one taken
//      before it (the chain), else it is a copy given another serial;
//   7. the handler says Take, Later (its turn has not come: offered again
//      after the next message taken, with its channel's later messages behind
//      it) or Refuse (it cannot be the channel's next message: dropped, and
//      the serial is expected again; the same message refused again, once
//      asked for, fails the run naming the channel, rather than being asked
//      for without end).
//
// A bad message is dropped with one log line naming the channel and the field,
// and counted (drops()). An exception from a handler never leaves the edge: the
// edge stops taking the run's messages and reports the failure (the process
// then says FAILED). What it sends is tagged on a keyed bus, and refused (an
// exception naming the channel) if it is larger than protocol.bus.max_message_bytes.
// Channels in:  those subscribed; RESEND (when it answers for what it published)
// Channels out: RESEND (asking), and what the owner publishes
#pragma once
#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "afford/auth.hpp"
#include "afford/decode.hpp"
#include "afford/names.hpp"
#include "afford/config.hpp"
#include "afford/protocol.hpp"
#include "afford/seal.hpp"
#include "afford/serials.hpp"
#include "afford/wire.hpp"

namespace afford {

// What a handler makes of a message offered to it.
class Turn {
 public:
  enum class Kind { Take, Later, Refuse };
  static Turn take() { return Turn(Kind::Take, {}); }
  static Turn later() { return Turn(Kind::Later, {}); }
  static Turn refuse(std::string why) { return Turn(Kind::Refuse, std::move(why)); }
  Kind kind() const { return kind_; }
  const std::string& why() const { return why_; }

 private:
  Turn(Kind k, std::string why) : kind_(k), why_(std::move(why)) {}
  Kind kind_;
  std::string why_;
};

// The bytes a message arrived as (for a handler that records them).
struct Envelope {
  const std::string& channel;
  const std::uint8_t* data;
  std::size_t size;
  std::int64_t recv_utime;
};

// Which runs' messages a subscription takes.
enum class Scope {
  Run,        // the run joined; nothing while none is
  RunOrAny,   // the run joined; every run while none is (observers)
  Any,        // every message (control channels, STATUS)
};
// How a subscription orders a channel (types with a serial).
enum class Order {
  Serial,   // in serial order, once; missing messages asked for
  Follow,   // in serial order, once, but a gap is skipped (observers, which ask for nothing)
  None,     // as they come (types without a serial)
};


// The run id a message starts with, read without decoding it; false if the
// buffer cannot hold one of at most `max_bytes`.
bool peekRunId(const void* data, std::size_t size, int max_bytes, std::string& out);

// The first fields of every run message (a channel with a serial): run_id,
// step, serial, read without decoding. False if the buffer is too short to
// hold them (tests/unit/test_logger.cpp pins the layout for every type with a
// serial). Used where messages are counted, not taken: the logger's earlier
// segments, replay's gaps.
struct RunHeader {
  std::string run_id;
  std::int64_t step = 0, serial = 0;
};
bool peekRunHeader(const void* data, std::size_t size, RunHeader& out);

// What an edge dropped, by kind (each also a log line).
struct EdgeDrops {
  std::int64_t untagged = 0;        // no valid tag on a keyed bus
  std::int64_t refused = 0;         // every other message dropped: malformed, forged, another run's, ...
  std::int64_t peers_forgotten = 0; // (process, pid) pairs forgotten beyond protocol.limits.peers
};

class Edge {
 public:
  // `owner`: the process (or tool) this edge belongs to, named in its requests.
  Edge(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, std::string owner, const ProtocolConfig& protocol);
  ~Edge();  // unsubscribes: the bus may outlive the edge (a restart in one process)
  Edge(const Edge&) = delete;
  Edge& operator=(const Edge&) = delete;

  // On a keyed bus, every message sent is tagged and every message received
  // must be (nullptr: no key). Set before the first message is handled.
  void useKey(std::shared_ptr<const BusKey> key) { key_ = std::move(key); }
  const std::shared_ptr<const BusKey>& key() const { return key_; }
  const EdgeDrops& drops() const { return drops_; }

  // ---- the run served -----------------------------------------------------------
  // Serve `run_id` with `config` (kept by the caller, alive until leave()):
  // ordering, deferral and history start anew; the run's protocol applies.
  void join(const std::string& run_id, const RunConfig* config);
  // Leave the run: its messages are dropped from now on; the history of what
  // was published stays, to answer late requests, until the next join().
  void leave();
  const std::string& run() const { return run_; }
  const RunConfig* config() const { return config_; }
  const ProtocolConfig& protocol() const { return *protocol_; }
  BoundsContext context() const { return {protocol_, config_}; }
  // Other runs' messages: a warning (processes) or a debug line (the runner).
  void warnOtherRuns(bool on) { warn_other_runs_ = on; }
  // Called when a handler throws or a bound is reached: (channel, reason).
  // The edge has already stopped taking the run's messages.
  void onFailure(std::function<void(const std::string&, const std::string&)> f) { on_failure_ = std::move(f); }
  bool failed() const { return failed_; }
  // Stop taking the run's messages (the owner failed for another reason).
  void suspend() {
    failed_ = true;
    deferred_.clear();
  }
  // Offer the waiting messages again (the owner's state changed, e.g. START).
  void retry() { retryDeferred(); }

  // ---- receiving ----------------------------------------------------------------
  // `handler` is called as Turn(const Msg&) or Turn(const Msg&, const Envelope&), Msg being the
  // channel's type (afford/protocol.hpp): a handler of another type does not compile.
  template <class Msg, class F>
  void subscribe(const Channel<Msg>& channel, F handler, Scope scope, Order order);
  // Take a publisher's counts (its STATUS) as claims on the channels it publishes.
  void claim(const process_status_t& status);
  // Ask for what is missing, if due (call from the loop too: retries).
  void askMissing();
  std::int64_t missing() const { return serials_.missing(); }
  // The channels taken in serial order (Order::Serial): those whose gaps are asked for.
  const std::vector<std::string>& ordered() const { return tracked_; }
  std::map<std::string, std::pair<std::int64_t, std::int64_t>> missingRanges() const { return serials_.missingRanges(); }
  // A restarted recorder goes on from where its earlier record ends: `next`
  // is the serial to expect, `last_digest` the digest of the one before it.
  void expectSerial(const std::string& channel, std::int64_t next, std::int64_t last_digest);
  std::size_t deferred() const { return deferred_.size(); }
  // Last time a message of the run was taken or published.
  std::chrono::steady_clock::time_point lastActivity() const { return last_activity_; }
  // How long this process usually waits, after publishing, for the next message it takes (a moving average
  // over the runs so far): the pace of the runs on this machine, which a lost message breaks.
  std::chrono::steady_clock::duration usualWait() const { return usual_wait_; }
  // The process announced its counts while it waited: the wait may be a loss's, not the pace (counting it would
  // lengthen the next waits before an announcement, and so the next losses' waits).
  void waitAnnounced() { awaiting_ = false; }
  // When the edge next has something to do by itself (a request's retry).
  std::chrono::steady_clock::time_point nextDue() const { return serials_.nextDue(); }

  // ---- publishing ------------------------------------------------------------------
  // A run message: the channel's next serial and the digest are set; its bytes
  // are kept in the run's history to answer RESEND.
  template <class Msg>
  void publish(const Channel<Msg>& channel, Msg& msg);
  // A message without a serial (RUN_CONFIG, RUN_CONTROL, STATUS, RESEND): sealed and sent.
  template <class Msg>
  void send(const Channel<Msg>& channel, Msg& msg) {
    static_assert(!wire::Bounds<Msg>::kSerial, "a run message is published (serial, chain, history), not sent");
    transmit(channel.name, sealed(msg));
  }
  // Answer RESEND requests for what this edge published (processes).
  void answerResends();
  // Per channel published in the history's run: how many messages.
  std::vector<std::pair<std::string, std::int64_t>> counts() const;
  const std::string& historyRun() const { return history_run_; }

 private:
  struct Subscription {
    std::function<void(const lcm::ReceiveBuffer*)> fn;
    lcm::Subscription* sub = nullptr;
    void on(const lcm::ReceiveBuffer* b, const std::string&) { fn(b); }
  };
  struct Pending {
    std::string channel;
    std::int64_t serial = -1;
    std::int64_t digest = 0;
    std::function<Turn()> call;
  };
  // The digests of a channel's messages taken in order, from serial `first`.
  struct Chain {
    std::int64_t first = 0;
    std::vector<std::int64_t> digests;
    bool knows(std::int64_t serial) const {
      return serial >= first && serial < first + static_cast<std::int64_t>(digests.size());
    }
  };
  // Does a message at the channel's expected serial follow the one taken before it?
  bool follows(const std::string& channel, std::int64_t serial, std::int64_t prev_digest, Order order);
  void chained(const std::string& channel, std::int64_t serial, std::int64_t digest);
  struct History {
    std::int64_t last_digest = 0;
    std::vector<std::vector<std::uint8_t>> messages;
    std::vector<std::chrono::steady_clock::time_point> republished;  // last republication of each
    std::chrono::steady_clock::time_point window{};                  // start of the budget window
    int in_window = 0;                                                // republished in it
  };

  template <class Msg, class F>
  void receive(const std::string& channel, const lcm::ReceiveBuffer* rb, const std::shared_ptr<const F>& handler,
               Scope scope, Order order);
  // Onto the bus: the size checked, tagged on a keyed bus.
  void transmit(const std::string& channel, const std::vector<std::uint8_t>& bytes);
  // Step 0: the message without its tag, or false (dropped) on a keyed bus without a valid one.
  bool untag(const std::string& channel, const lcm::ReceiveBuffer* rb, std::size_t& size);
  bool inScope(const std::string& channel, const std::string& run_id, Scope scope);
  void drop(const std::string& channel, const std::string& why);
  // Offer an accepted serial message (or queue it behind its channel's waiting ones).
  void dispatch(Pending p);
  Turn::Kind attempt(Pending& p);
  void retryDeferred();
  void refused(const Pending& p, const std::string& why);
  void fail(const std::string& channel, const std::string& why);
  bool blocked(const std::string& channel) const;
  void onResend(const resend_t& r);
  // Is this STATUS newer (by beat) than the last one taken from its process and pid?
  bool newerStatus(const process_status_t& st);

  lcm::LCM& lcm_;
  std::shared_ptr<spdlog::logger> log_;
  std::string owner_;
  const ProtocolConfig* protocol_;
  ProtocolConfig own_protocol_;  // between runs
  std::vector<std::unique_ptr<Subscription>> subs_;
  std::string run_;
  const RunConfig* config_ = nullptr;
  bool warn_other_runs_ = true;
  bool failed_ = false;
  std::function<void(const std::string&, const std::string&)> on_failure_;
  SerialTracker serials_;
  std::vector<std::string> tracked_;       // channels taken in serial order (and asked for)
  std::deque<Pending> deferred_;
  bool retrying_ = false;
  std::chrono::steady_clock::time_point last_activity_{};
  std::chrono::steady_clock::time_point last_published_{};
  bool awaiting_ = false;  // published since the last message taken
  std::chrono::steady_clock::duration usual_wait_{};
  std::map<std::string, Chain> chains_;     // what was taken, by channel
  // The last message refused on each channel (serial, digest): the same one
  // refused again, after it was asked for, is the channel's genuine message
  // that its handler will never take, and the run fails rather than ask forever.
  std::map<std::string, std::pair<std::int64_t, std::int64_t>> refused_;
  std::map<std::string, History> history_;  // what this edge published, by channel
  std::string history_run_;
  bool answering_ = false;
  struct Beat {
    std::int64_t beat = -1;
    std::uint64_t order = 0;  // when it was last updated (for evicting the oldest)
  };
  std::map<std::string, Beat> beats_;  // process#pid -> the last STATUS taken (protocol.limits.peers)
  std::uint64_t beat_order_ = 0;
  std::shared_ptr<const BusKey> key_;
  EdgeDrops drops_;
};

// ---- template definitions ------------------------------------------------------------

namespace detail {
template <class Msg, class F>
Turn invokeHandler(const F& handler, const Msg& msg, const Envelope& envelope) {
  if constexpr (std::is_invocable_r_v<Turn, const F&, const Msg&, const Envelope&>)
    return handler(msg, envelope);
  else
    return handler(msg);
}
}  // namespace detail

template <class Msg, class F>
void Edge::subscribe(const Channel<Msg>& typed, F handler, Scope scope, Order order) {
  static_assert(std::is_invocable_r_v<Turn, const F&, const Msg&, const Envelope&> ||
                    std::is_invocable_r_v<Turn, const F&, const Msg&>,
                "a handler is Turn(const Msg&) or Turn(const Msg&, const Envelope&), Msg the channel's type");
  const std::string channel = typed.name;
  if (!wire::Bounds<Msg>::kSerial && order != Order::None)
    throw std::logic_error(channel + ": afford." + wire::Bounds<Msg>::kName + " has no serial to order by");
  auto shared = std::make_shared<const F>(std::move(handler));
  auto s = std::make_unique<Subscription>();
  s->fn = [this, channel, shared, scope, order](const lcm::ReceiveBuffer* rb) {
    try {
      receive<Msg>(channel, rb, shared, scope, order);
    } catch (const std::exception& e) {
      fail(channel, e.what());
    } catch (...) {
      fail(channel, "an unknown exception");
    }
  };
  s->sub = lcm_.subscribe(channel, &Subscription::on, s.get());
  s->sub->setQueueCapacity(protocol_->queue_capacity);
  if (order == Order::Serial) tracked_.push_back(channel);
  subs_.push_back(std::move(s));
}

template <class Msg, class F>
void Edge::receive(const std::string& channel, const lcm::ReceiveBuffer* rb, const std::shared_ptr<const F>& handler,
                   Scope scope, Order order) {
  const auto* data = static_cast<const std::uint8_t*>(rb->data);
  std::size_t size = rb->data_size;
  if (!untag(channel, rb, size)) return;
  std::int64_t hash = 0;
  if (size < 8 || (__int64_t_decode_array(data, 0, 8, &hash, 1), hash != Msg::getHash()))
    return drop(channel, std::string("wrong fingerprint: not an afford.") + wire::Bounds<Msg>::kName);
  std::string run_id;
  if (!peekRunId(data, size, protocol_->limits.name_bytes, run_id))
    return drop(channel, "field run_id: no string of at most " + std::to_string(protocol_->limits.name_bytes) +
                             " bytes where it begins");
  if (!run_id.empty()) {
    if (std::string why = runIdProblem(run_id, protocol_->limits.run_id_bytes); !why.empty())
      return drop(channel, "field run_id '" + printable(run_id, 80) + "' " + why);
  }
  if (!inScope(channel, run_id, scope)) return;
  auto msg = std::make_shared<Msg>();
  std::string why;
  if (!decodeChecked(data, size, context(), *msg, why)) return drop(channel, why);
  if constexpr (std::is_same_v<Msg, process_status_t>) {
    if (!newerStatus(*msg)) return log_->trace("{}: an old STATUS of {} (pid {}) again", channel, msg->process, msg->pid);
  }

  if (order == Order::None) {
    const Turn t = detail::invokeHandler(*handler, *msg, Envelope{channel, data, size, rb->recv_utime});
    if (t.kind() == Turn::Kind::Refuse) drop(channel, t.why());
    return;
  }
  if constexpr (wire::Bounds<Msg>::kSerial) {
    if (msg->serial == serials_.expected(channel) && !follows(channel, msg->serial, msg->prev_digest, order))
      return drop(channel, "field prev_digest does not follow the channel's message " + std::to_string(msg->serial - 1) +
                               " (a copy given another serial, or another run's)");
    switch (serials_.offer(channel, msg->serial)) {
      case SerialTracker::Verdict::Repeat:
        log_->trace("{}: serial {} already had (a repeat)", channel, msg->serial);
        return;
      case SerialTracker::Verdict::Gap:
        if (order == Order::Follow) {  // an observer goes on from here
          serials_.expect(channel, msg->serial);
          serials_.offer(channel, msg->serial);
          break;
        }
        log_->debug("{}: serial {} came before serial {}: asking for the missing ones", channel, msg->serial,
                    serials_.expected(channel));
        askMissing();
        return;
      case SerialTracker::Verdict::Beyond:
        return drop(channel, "field serial = " + std::to_string(msg->serial) + " is at or beyond the " +
                                 std::to_string(serials_.finalCount(channel)) +
                                 " messages its publisher published in the run before it left");
      case SerialTracker::Verdict::Accept:
        break;
    }
    chained(channel, msg->serial, msg->digest);
    Pending p;
    p.channel = channel;
    p.serial = msg->serial;
    p.digest = msg->digest;
    if constexpr (std::is_invocable_r_v<Turn, const F&, const Msg&, const Envelope&>) {
      // The bytes outlive this callback if the message has to wait its turn.
      auto bytes = std::make_shared<const std::vector<std::uint8_t>>(data, data + size);
      p.call = [handler, msg, bytes, channel, utime = rb->recv_utime]() {
        return (*handler)(*msg, Envelope{channel, bytes->data(), bytes->size(), utime});
      };
    } else {
      p.call = [handler, msg]() { return (*handler)(*msg); };
    }
    dispatch(std::move(p));
    if (order == Order::Serial && serials_.missing() > 0) askMissing();
  }
}

template <class Msg>
void Edge::publish(const Channel<Msg>& typed, Msg& msg) {
  static_assert(wire::Bounds<Msg>::kSerial, "a message without a serial is sent, not published");
  const std::string channel = typed.name;
  History& h = history_[channel];
  msg.serial = static_cast<std::int64_t>(h.messages.size());
  msg.prev_digest = h.messages.empty() ? chainSeed(history_run_, channel) : h.last_digest;
  std::vector<std::uint8_t> bytes = sealed(msg);
  transmit(channel, bytes);
  h.last_digest = msg.digest;
  h.messages.push_back(std::move(bytes));
  h.republished.emplace_back();
  last_activity_ = last_published_ = std::chrono::steady_clock::now();
  awaiting_ = true;
}

}  // namespace afford
