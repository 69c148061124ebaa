// The edge's outbound part (afford/edge.hpp): what a process published in the
// run, kept to answer RESEND. A run message is given the channel's next serial
// and the digest of the one before it (the chain) as it is published; a
// RESEND for what is kept is answered within a budget (protocol.resend_cap
// per request, protocol.resend_budget per channel and retry_ms; a copy just
// republished serves a request that comes right after). It sends nothing
// itself: a republication goes out through the callback it was given.
#pragma once
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "afford/config.hpp"
#include "afford/resend_t.hpp"

namespace afford {

class EdgeOutbound {
 public:
  using Clock = std::chrono::steady_clock;
  using Transmit = std::function<void(const std::string& channel, const std::vector<std::uint8_t>& bytes)>;

  EdgeOutbound(std::shared_ptr<spdlog::logger> log, Transmit transmit);

  // A run joined: what is published from now is that run's (what the last run published is forgotten).
  void join(const std::string& run_id);
  const std::string& run() const { return run_; }

  // A run message about to be sealed on `channel`: its serial and the digest it follows.
  std::int64_t nextSerial(const std::string& channel) const;
  std::int64_t lastDigest(const std::string& channel) const;
  // ... and once sealed (its digest known) and sent: kept.
  void kept(const std::string& channel, std::int64_t digest, std::vector<std::uint8_t> bytes);

  // A RESEND: what is asked of this publisher's history republished, within the protocol's budget.
  void answer(const resend_t& r, const ProtocolConfig& protocol);
  // Per channel published in the run: how many messages.
  std::vector<std::pair<std::string, std::int64_t>> counts() const;

 private:
  struct History {
    std::int64_t last_digest = 0;
    std::vector<std::vector<std::uint8_t>> messages;
    std::vector<Clock::time_point> republished;  // last republication of each
    Clock::time_point window{};                  // start of the budget window
    int in_window = 0;                           // republished in it
  };
  std::shared_ptr<spdlog::logger> log_;
  Transmit transmit_;
  std::string run_;
  std::map<std::string, History> history_;  // by channel
};

}  // namespace afford
