// The edge's inbound part (afford/edge.hpp, steps 6 and 7): the run's
// messages taken in serial order, once, each channel's chain of digests
// followed, the messages whose turn has not come deferred (bounded by
// protocol.max_deferred), refusals (a serial refused twice fails the run),
// what is missing asked for (RESEND), and the pace of the process's inputs
// (how long it usually waits after publishing). It sends nothing itself: a
// request goes out through the callback it was given.
#pragma once
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "afford/config.hpp"
#include "afford/process_status_t.hpp"
#include "afford/resend_t.hpp"
#include "afford/serials.hpp"

namespace afford {

// Which request of a run a subscriber serves (run_config_t): the digest of its RUN_CONFIG, by which STATUS,
// RUN_CONTROL and RESEND name it, and its request number, from which every channel's chain starts
// (afford/seal.hpp). A replay that changes the recorded configuration (and so its digest) keeps the number.
struct RequestId {
  std::int64_t config_digest = 0;
  std::int64_t number = 0;
};

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

// How a subscription orders a channel (types with a serial).
enum class Order {
  Serial,   // in serial order, once; missing messages asked for
  Follow,   // in serial order, once, but a gap is skipped (observers, which ask for nothing)
  None,     // as they come (types without a serial)
};

class EdgeInbound {
 public:
  using Clock = std::chrono::steady_clock;
  // A message accepted in order, waiting to be offered to its handler.
  struct Pending {
    std::string channel;
    std::int64_t serial = -1;
    std::int64_t digest = 0;
    std::function<Turn()> call;
  };
  // What the inbound part needs of its edge: a dropped message's line and count, and RESEND sent.
  struct Hooks {
    std::function<void(const std::string& channel, const std::string& why)> drop;
    std::function<void(resend_t&)> ask;
  };

  EdgeInbound(std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol, Hooks hooks);

  // A run joined (its request; its protocol) or left: everything about the last run's order is forgotten.
  void join(const std::string& run_id, RequestId request, const RunConfig* config, const ProtocolConfig& protocol);
  void leave(const ProtocolConfig& protocol);
  // A channel taken in serial order (Order::Serial): its gaps are asked for.
  void track(const std::string& channel) { tracked_.push_back(channel); }
  const std::vector<std::string>& tracked() const { return tracked_; }

  // Step 6 for a run message: where its serial stands (the chain checked for the expected one). Returns ""
  // if it is to be dispatched, or why it was dropped ("" with `skip` true: a repeat, or a gap asked for).
  std::string order(const std::string& channel, std::int64_t serial, std::int64_t prev_digest, std::int64_t digest,
                    Order order, bool& skip);
  // Step 7: offer an accepted message to its handler (or queue it behind its channel's waiting ones).
  void dispatch(Pending p);
  void retryDeferred();
  void fail(const std::string& channel, const std::string& why);
  bool failed() const { return failed_; }
  void suspend() {
    failed_ = true;
    deferred_.clear();
  }
  void onFailure(std::function<void(const std::string&, const std::string&)> f) { on_failure_ = std::move(f); }

  // A publisher's counts (its STATUS) as claims on the channels it publishes, if they are of the request
  // served.
  void claim(const process_status_t& status);
  // Why this process cannot go on, if a message of its own run stands in its way: the last message at a
  // channel's expected serial that was dropped or refused since a message was last taken ("CHANNEL serial N
  // (published by P): why, K times"), "" while its inputs flow.
  std::string stuck() const;
  // Ask for what is missing, if due.
  void askMissing();
  std::int64_t missing() const { return serials_.missing(); }
  std::map<std::string, std::pair<std::int64_t, std::int64_t>> missingRanges() const { return serials_.missingRanges(); }
  void expectSerial(const std::string& channel, std::int64_t next, std::int64_t last_digest);
  // Where a channel taken in order stands for its handler: the next serial it has not had (taken, or
  // ignored by a rule), and the digest of the one before it. A restart from a snapshot taken now would
  // take each channel again from there (restore()).
  struct Position {
    std::string channel;
    std::int64_t next = 0, last_digest = 0;
  };
  std::vector<Position> positions() const;
  void restore(const std::vector<Position>& at);
  std::size_t deferred() const { return deferred_.size(); }
  Clock::time_point nextDue() const { return serials_.nextDue(); }

  // The pace: a message taken or published is activity; the wait after publishing for the next message taken
  // is averaged (usualWait); a wait in which the process announced its counts is not counted.
  void published() {
    last_activity_ = last_published_ = Clock::now();
    awaiting_ = true;
  }
  Clock::time_point lastActivity() const { return last_activity_; }
  Clock::duration usualWait() const { return usual_wait_; }
  void waitAnnounced() { awaiting_ = false; }

 private:
  // The digests of a channel's messages taken in order, from serial `first`.
  struct Chain {
    std::int64_t first = 0;
    std::vector<std::int64_t> digests;
    bool knows(std::int64_t serial) const {
      return serial >= first && serial < first + static_cast<std::int64_t>(digests.size());
    }
  };
  bool follows(const std::string& channel, std::int64_t serial, std::int64_t prev_digest, Order order);
  void chained(const std::string& channel, std::int64_t serial, std::int64_t digest);
  Turn::Kind attempt(Pending& p);
  void refused(const Pending& p, const std::string& why);
  bool blocked(const std::string& channel) const;

  std::shared_ptr<spdlog::logger> log_;
  const ProtocolConfig* protocol_;
  Hooks hooks_;
  std::string run_;
  RequestId request_;
  const RunConfig* config_ = nullptr;
  bool failed_ = false;
  std::function<void(const std::string&, const std::string&)> on_failure_;
  SerialTracker serials_;
  std::vector<std::string> tracked_;
  std::deque<Pending> deferred_;
  bool retrying_ = false;
  Clock::time_point last_activity_{};
  Clock::time_point last_published_{};
  bool awaiting_ = false;  // published since the last message taken
  Clock::duration usual_wait_{};
  std::map<std::string, Chain> chains_;  // what was accepted, by channel, from the one before the next to handle
  std::map<std::string, std::pair<std::int64_t, std::int64_t>> handled_;  // channel -> next serial, digest before it
  void handled(const Pending& p);
  // The last message refused on each channel (serial, digest): the same one
  // refused again, after it was asked for, is the channel's genuine message
  // that its handler will never take, and the run fails rather than ask forever.
  std::map<std::string, std::pair<std::int64_t, std::int64_t>> refused_;
  // The last expected message dropped or refused since one was last taken (stuck()).
  struct Stuck {
    std::string channel, why;
    std::int64_t serial = -1, times = 0;
  } stuck_;
  void stuckOn(const std::string& channel, std::int64_t serial, const std::string& why);
};

}  // namespace afford
