// The message edge: the one place where bytes from the bus become typed
// messages (docs/processes-and-channels.md, "The message edge"). Every
// subscriber goes through it: the processes (NodeBase), the runner, the
// viewer, `afford status` and replay. For each datagram, in this order:
//
//   0. tag: on a bus with a key (afford/auth.hpp), the trailer must hold the
//      tag of the rest on this channel, else the message is dropped and
//      counted; and its stamp must be fresh (afford/edge_peers.hpp): a message
//      said again (taken already, or a recording's) is dropped and counted.
//      The trailer is taken off, and the steps below see the message;
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
// A bad message is dropped and counted (drops()); the first few of each kind
// with a line naming the channel and the field, the rest in summaries
// (afford/drop_log.hpp). An exception from a handler never leaves the edge: the
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
#include "afford/drop_log.hpp"
#include "afford/edge_inbound.hpp"
#include "afford/edge_outbound.hpp"
#include "afford/edge_peers.hpp"
#include "afford/names.hpp"
#include "afford/config.hpp"
#include "afford/protocol.hpp"
#include "afford/seal.hpp"
#include "afford/serials.hpp"
#include "afford/snapshot.hpp"
#include "afford/wire.hpp"

namespace afford {

// The request a RUN_CONFIG asks for.
inline RequestId requestOf(const run_config_t& m) { return {m.digest, m.request}; }

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
  KeyMismatches key;                // the reader's key does not fit the bus: tagged, untagged, another key's
  std::int64_t replayed = 0;        // a keyed bus's message said again: taken already, or too old (freshness)
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
  // What is published is not held for a RESEND or a restart (EdgeOutbound::holdNothing).
  void holdNothingPublished() { outbound_.holdNothing(); }
  const std::shared_ptr<const BusKey>& key() const { return key_; }
  const EdgeDrops& drops() const { return drops_; }

  // ---- the run served -----------------------------------------------------------
  // Serve `request` of `run_id` with `config` (kept by the caller, alive until leave()): ordering, deferral
  // and history start anew, even for a run id served before; every channel's chain starts from the request
  // (afford/seal.hpp); the run's protocol applies.
  void join(const std::string& run_id, const RunConfig* config, RequestId request);
  // Leave the run: its messages are dropped from now on; the history of what
  // was published stays, to answer late requests of that request, until the next join().
  void leave();
  // Forget what was published in the run left (a process leaving a run that goes on: its STATUS then
  // claims no counts of it, so none becomes final).
  void forgetPublished() { outbound_.join("", {}, protocol_->recovery, {}); }
  const std::string& run() const { return run_; }
  const RequestId& request() const { return request_; }
  const RunConfig* config() const { return config_; }
  const ProtocolConfig& protocol() const { return *protocol_; }
  BoundsContext context() const { return {protocol_, config_}; }
  // Other runs' messages: a warning (processes) or a debug line (the runner).
  void warnOtherRuns(bool on) { warn_other_runs_ = on; }
  // Called when a handler throws or a bound is reached: (channel, reason).
  // The edge has already stopped taking the run's messages.
  void onFailure(std::function<void(const std::string&, const std::string&)> f) { inbound_.onFailure(std::move(f)); }
  bool failed() const { return inbound_.failed(); }
  // Called after each message has been dealt with (taken, deferred or dropped), outside every handler: the
  // process's state is between two messages (NodeBase takes its snapshots there).
  void onQuiet(std::function<void()> f) { on_quiet_ = std::move(f); }
  // Stop taking the run's messages (the owner failed for another reason).
  void suspend() { inbound_.suspend(); }
  // Offer the waiting messages again (the owner's state changed, e.g. START).
  void retry() { inbound_.retryDeferred(); }

  // ---- receiving ----------------------------------------------------------------
  // `handler` is called as Turn(const Msg&) or Turn(const Msg&, const Envelope&), Msg being the
  // channel's type (afford/protocol.hpp): a handler of another type does not compile.
  template <class Msg, class F>
  void subscribe(const Channel<Msg>& channel, F handler, Scope scope, Order order);
  // Take a subscribed channel from the bus (on), or stop taking it: while off, this process is not
  // subscribed to it and LCM's socket filter drops its datagrams in the kernel. For a passive listener
  // that samples a busy channel (afford watch); a process in a run never turns a channel off. Throws
  // std::logic_error if `channel` was not subscribed. Not from a handler.
  void take(const std::string& channel, bool on);
  // Take a publisher's counts (its STATUS) as claims on the channels it publishes, and a reader's
  // restart positions as what it may still ask of what this process published.
  void claim(const process_status_t& status) {
    inbound_.claim(status);
    outbound_.readerSaid(status);
  }
  // Ask for what is missing, if due (call from the loop too: retries).
  void askMissing() { inbound_.askMissing(); }
  std::int64_t missing() const { return inbound_.missing(); }
  // The channels taken in serial order (Order::Serial): those whose gaps are asked for.
  const std::vector<std::string>& ordered() const { return inbound_.tracked(); }
  std::map<std::string, std::pair<std::int64_t, std::int64_t>> missingRanges() const { return inbound_.missingRanges(); }
  // A restarted recorder goes on from where its earlier record ends: `next`
  // is the serial to expect, `last_digest` the digest of the one before it.
  void expectSerial(const std::string& channel, std::int64_t next, std::int64_t last_digest) {
    inbound_.expectSerial(channel, next, last_digest);
  }
  std::size_t deferred() const { return inbound_.deferred(); }
  // Last time a message of the run was taken or published.
  std::chrono::steady_clock::time_point lastActivity() const { return inbound_.lastActivity(); }
  // How long this process usually waits, after publishing, for the next message it takes (a moving average
  // over the runs so far): the pace of the runs on this machine, which a lost message breaks.
  std::chrono::steady_clock::duration usualWait() const { return inbound_.usualWait(); }
  // The process announced its counts while it waited: the wait may be a loss's, not the pace (counting it would
  // lengthen the next waits before an announcement, and so the next losses' waits).
  void waitAnnounced() { inbound_.waitAnnounced(); }
  // When the edge next has something to do by itself (a request's retry).
  std::chrono::steady_clock::time_point nextDue() const { return inbound_.nextDue(); }

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
  // Per channel published in the history's run: how many messages, and the first still held.
  std::vector<EdgeOutbound::Count> counts() const { return outbound_.counts(); }
  bool publishedAny() const { return outbound_.any(); }
  // Per channel taken in serial order: the next serial its handler has not had, and the digest before it
  // (where a restart from a snapshot taken now would take it again).
  std::vector<EdgeInbound::Position> positions() const { return inbound_.positions(); }
  // The snapshot's part of the edge: what was handled of each channel taken, and what was published.
  void save(SnapshotWriter& w) const;
  void load(SnapshotReader& r);
  const std::string& historyRun() const { return outbound_.run(); }
  std::int64_t historyConfig() const { return outbound_.request().config_digest; }
  // Why this process cannot go on, if a message of its run stands in its way (EdgeInbound::stuck()).
  std::string stuck() const { return inbound_.stuck(); }
  // Say what was dropped and not said yet (the drops' summary), e.g. at the end of a process.
  void flushDrops() { drop_log_.flush(); }

 private:
  struct Subscription {
    std::string channel;
    std::function<void(const lcm::ReceiveBuffer*)> fn;
    lcm::Subscription* sub = nullptr;  // null while the channel is not taken (take())
    void on(const lcm::ReceiveBuffer* b, const std::string&) { fn(b); }
  };
  using Pending = EdgeInbound::Pending;

  template <class Msg, class F>
  void receive(const std::string& channel, const lcm::ReceiveBuffer* rb, const std::shared_ptr<const F>& handler,
               Scope scope, Order order);
  // Onto the bus: the size checked, tagged on a keyed bus.
  void transmit(const std::string& channel, const std::vector<std::uint8_t>& bytes);
  // Step 0: the message without its tag, or false (dropped) on a keyed bus without a valid one.
  bool untag(const std::string& channel, const lcm::ReceiveBuffer* rb, std::size_t& size);
  bool inScope(const std::string& channel, const lcm::ReceiveBuffer* rb, const std::string& run_id, Scope scope);
  void drop(const std::string& channel, const std::string& why);
  // A message heard dropped before its handler: as a key that does not fit the bus (a reader without a key
  // hearing a tagged one, afford/auth.hpp), else for `why`.
  void refuse(const std::string& channel, const lcm::ReceiveBuffer* rb, const std::string& why);
  void fail(const std::string& channel, const std::string& why) { inbound_.fail(channel, why); }
  // Is this STATUS newer (by beat) than the last one taken from its process and pid?
  bool newerStatus(const process_status_t& st) {
    return peers_.newerStatus(st, protocol_->limits.peers, drops_.peers_forgotten);
  }

  lcm::LCM& lcm_;
  std::shared_ptr<spdlog::logger> log_;
  std::string owner_;
  const ProtocolConfig* protocol_;
  ProtocolConfig own_protocol_;  // between runs
  std::vector<std::unique_ptr<Subscription>> subs_;
  std::string run_;
  RequestId request_;
  const RunConfig* config_ = nullptr;
  bool warn_other_runs_ = true;
  bool answering_ = false;
  int receiving_ = 0;  // messages being dealt with (a handler's publication may be delivered at once)
  std::function<void()> on_quiet_;
  std::shared_ptr<const BusKey> key_;
  const std::uint64_t session_ = BusKey::newSession();  // this edge's, under its tags (a keyed bus)
  std::uint64_t sent_ = 0;                              // tagged messages sent: the next one's counter
  EdgeDrops drops_;
  DropLog drop_log_;       // the lines about drops, counted and summarised
  EdgeInbound inbound_;    // the run's messages in order: chains, deferral, refusals, asking (steps 6 and 7)
  EdgeOutbound outbound_;  // what was published: serials, history, answering RESEND
  EdgePeers peers_;        // the processes heard (their STATUS beats)
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
  s->channel = channel;
  s->fn = [this, channel, shared, scope, order](const lcm::ReceiveBuffer* rb) {
    ++receiving_;
    try {
      receive<Msg>(channel, rb, shared, scope, order);
    } catch (const std::exception& e) {
      fail(channel, e.what());
    } catch (...) {
      fail(channel, "an unknown exception");
    }
    if (--receiving_ == 0 && on_quiet_) on_quiet_();
  };
  s->sub = lcm_.subscribe(channel, &Subscription::on, s.get());
  s->sub->setQueueCapacity(protocol_->queue_capacity);
  if (order == Order::Serial) inbound_.track(channel);
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
    return refuse(channel, rb, std::string("wrong fingerprint: not an afford.") + wire::Bounds<Msg>::kName);
  std::string run_id;
  if (!peekRunId(data, size, protocol_->limits.name_bytes, run_id))
    return refuse(channel, rb, "field run_id: no string of at most " + std::to_string(protocol_->limits.name_bytes) +
                                   " bytes where it begins");
  if (!run_id.empty()) {
    if (std::string why = runIdProblem(run_id, protocol_->limits.run_id_bytes); !why.empty())
      return refuse(channel, rb, "field run_id '" + printable(run_id, 80) + "' " + why);
  }
  if (!inScope(channel, rb, run_id, scope)) return;
  auto msg = std::make_shared<Msg>();
  std::string why;
  if (!decodeChecked(data, size, context(), *msg, why)) return refuse(channel, rb, why);
  if constexpr (std::is_same_v<Msg, process_status_t>) {
    if (!newerStatus(*msg)) return log_->trace("{}: an old STATUS of {} (pid {}) again", channel, msg->process, msg->pid);
  }

  if (order == Order::None) {
    const Turn t = detail::invokeHandler(*handler, *msg, Envelope{channel, data, size, rb->recv_utime});
    if (t.kind() == Turn::Kind::Refuse) drop(channel, t.why());
    return;
  }
  if constexpr (wire::Bounds<Msg>::kSerial) {
    bool skip = false;
    if (std::string why = inbound_.order(channel, msg->serial, msg->prev_digest, msg->digest, order, skip); !why.empty())
      return drop(channel, why);
    if (skip) return;
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
    inbound_.dispatch(std::move(p));
    if (order == Order::Serial && inbound_.missing() > 0) inbound_.askMissing();
  }
}

template <class Msg>
void Edge::publish(const Channel<Msg>& typed, Msg& msg) {
  static_assert(wire::Bounds<Msg>::kSerial, "a message without a serial is sent, not published");
  const std::string channel = typed.name;
  msg.serial = outbound_.nextSerial(channel);
  msg.prev_digest = outbound_.lastDigest(channel);
  std::vector<std::uint8_t> bytes = sealed(msg);
  transmit(channel, bytes);
  outbound_.kept(channel, msg.digest, std::move(bytes));
  inbound_.published();
}

}  // namespace afford
