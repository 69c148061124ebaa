// The edge's outbound part (afford/edge.hpp): what a process published in the
// run, held to answer RESEND. A run message is given the channel's next serial
// and the digest of the one before it (the chain) as it is published; a
// RESEND for what is held is answered within a budget (protocol.resend_cap
// per request, protocol.resend_budget per channel and retry_ms; a copy just
// republished serves a request that comes right after). It sends nothing
// itself: a republication goes out through the callback it was given.
//
// What is held is bounded (docs/processes-and-channels.md, "Runs of any
// length"): a channel's messages are let go once every process of the run
// that takes the channel has said (its STATUS) that a restart would take it
// again from a later serial (its latest snapshot's position), except the last
// protocol.recovery.history_keep of each channel; and whatever readers say,
// everything held stays under protocol.recovery.history_mb, the oldest let go
// first. STATUS says, per channel, the first serial still held.
#pragma once
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "afford/config.hpp"
#include "afford/edge_inbound.hpp"
#include "afford/process_status_t.hpp"
#include "afford/resend_t.hpp"

namespace afford {

class SnapshotWriter;
class SnapshotReader;

class EdgeOutbound {
 public:
  using Clock = std::chrono::steady_clock;
  using Transmit = std::function<void(const std::string& channel, const std::vector<std::uint8_t>& bytes)>;

  EdgeOutbound(std::shared_ptr<spdlog::logger> log, Transmit transmit);

  // A run joined: what is published from now is that request's (what the last one published is forgotten,
  // even under the same run id). `readers`: the processes of the run besides this one, whose restart positions
  // decide what is let go.
  void join(const std::string& run_id, RequestId request, const RecoveryConfig& recovery,
            std::vector<std::string> readers);
  const std::string& run() const { return run_; }
  const RequestId& request() const { return request_; }
  // Nothing published is held (a process fed a recording: no peer of its can ask it for anything).
  void holdNothing() { hold_nothing_ = true; }

  // A run message about to be sealed on `channel`: its serial and the digest it follows.
  std::int64_t nextSerial(const std::string& channel) const;
  std::int64_t lastDigest(const std::string& channel) const;
  // ... and once sealed (its digest known) and sent: held.
  void kept(const std::string& channel, std::int64_t digest, std::vector<std::uint8_t> bytes);

  // A RESEND of the request held: what is asked of this publisher's history republished, within the
  // protocol's budget (a RESEND of another request, of the same run id or not, is not answered).
  void answer(const resend_t& r, const ProtocolConfig& protocol);
  // A STATUS of a process of the request: where a restart of it would take each channel it takes again.
  void readerSaid(const process_status_t& st);

  struct Count {
    std::string channel;
    std::int64_t published = 0, held_from = 0;
  };
  // Per channel published in the run: how many messages, and the first still held.
  std::vector<Count> counts() const;
  bool any() const { return !history_.empty(); }
  std::size_t heldBytes() const { return bytes_; }
  std::int64_t letGoOverBound() const { return over_bound_; }  // messages let go by history_mb alone

  // The snapshot's part: per channel, the count, the chain's last digest and the messages held.
  void save(SnapshotWriter& w) const;
  void load(SnapshotReader& r, std::size_t max_message_bytes);

 private:
  struct History {
    std::int64_t first = 0;  // serial of messages.front()
    std::int64_t last_digest = 0;
    std::deque<std::vector<std::uint8_t>> messages;
    std::deque<Clock::time_point> republished;  // last republication of each
    std::size_t bytes = 0;
    Clock::time_point window{};                  // start of the budget window
    int in_window = 0;                           // republished in it
    std::int64_t count() const { return first + static_cast<std::int64_t>(messages.size()); }
  };
  void popFront(History& h);
  void letGo();  // by the readers' positions and history_keep
  void bound();  // by history_mb

  std::shared_ptr<spdlog::logger> log_;
  Transmit transmit_;
  std::string run_;
  RequestId request_;
  RecoveryConfig recovery_;
  std::map<std::string, History> history_;  // by channel
  std::size_t bytes_ = 0;                   // held, over every channel
  std::int64_t over_bound_ = 0;
  bool hold_nothing_ = false;
  std::set<std::string> readers_;                                    // the run's other processes
  std::map<std::string, std::map<std::string, std::int64_t>> from_;  // reader -> channel taken -> restart serial
};

}  // namespace afford
