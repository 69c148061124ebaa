// Reliable delivery over lossy multicast, by serial numbers.
//
// Every run message carries `serial`: its publisher's count of the messages it
// published earlier on that channel in the run. A receiver takes each channel
// strictly in serial order: a serial it has had is a repeat (dropped quietly);
// a serial beyond the next one means something was lost, and the receiver
// asks the publisher (RESEND) for the missing ones at once. Publishers claim
// how many messages they have published on each channel in their STATUS, so a
// receiver also notices a lost last message, and a restarted receiver pulls
// the whole run it missed. A channel's publisher is its only authority: its
// latest claim replaces its earlier ones and any higher serial seen before it,
// so a forged count or serial costs a few requests, never a wait. Once the
// publisher has left the run its count is final: a later claim can only
// lower it (the publisher publishes no more in a run it left, so a higher one
// is forged), and a serial at or beyond it is forged too, with no claim to
// come that would undo it: dropped, never waited for. The wall
// clock paces the requests only; it never decides what a process does with a
// message.
#pragma once
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace afford {

class SerialTracker {
 public:
  using Clock = std::chrono::steady_clock;
  // Beyond: at or past the publisher's final count (a forgery).
  enum class Verdict { Accept, Repeat, Gap, Beyond };
  struct Request {
    std::string channel;
    std::int64_t first = 0, last = 0;  // inclusive
  };

  // `batch`: most messages asked for at once; `retry`: how long an unanswered
  // request stands before it is asked again, doubling up to `retry_max`.
  SerialTracker(std::int64_t batch, Clock::duration retry, Clock::duration retry_max)
      : batch_(batch), retry_(retry), retry_max_(retry_max) {}

  void reset() { channels_.clear(); }
  // Start expecting `channel` at serial `next` (a restarted logger resumes its log).
  void expect(const std::string& channel, std::int64_t next);
  // A message arrived: Accept advances the channel's expected serial.
  Verdict offer(const std::string& channel, std::int64_t serial);
  // A message accepted at `serial` turned out not to be the channel's: expect
  // that serial again (the messages accepted after it are had no more).
  void rewind(const std::string& channel, std::int64_t serial);
  // The channel's publisher says it has published `count` messages; `final`:
  // it has left the run, so it will publish none there again.
  void claim(const std::string& channel, std::int64_t count, bool final = false);
  // The publisher's final count, or -1 while it has not left the run.
  std::int64_t finalCount(const std::string& channel) const;
  // Requests due now: each channel behind what is known to exist, at most
  // `batch` messages, not again while an earlier request stands, and only
  // for channels `may_ask` allows (a channel whose messages wait for their
  // turn asks for no more).
  std::vector<Request> due(Clock::time_point now, const std::function<bool(const std::string&)>& may_ask = {});
  // When the next standing request expires (time_point::max() if none).
  Clock::time_point nextDue() const;
  std::int64_t expected(const std::string& channel) const;
  std::int64_t missing() const;  // messages known to exist and not yet had, all channels
  // Per channel with missing messages: [expected, known).
  std::map<std::string, std::pair<std::int64_t, std::int64_t>> missingRanges() const;

 private:
  struct Channel {
    std::int64_t expected = 0;   // the next serial to accept
    std::int64_t claimed = 0;    // the publisher's latest claim
    std::int64_t evidence = 0;   // 1 + the highest serial seen since that claim
    std::int64_t final = -1;     // the least count it claimed once it had left the run; -1: it has not
    std::int64_t asked_last = -1, asked_from = -1;
    Clock::time_point asked_at{};
    Clock::duration wait{};      // how long the standing request stands
    std::int64_t known() const { return std::max(claimed, evidence); }
  };
  std::int64_t batch_;
  Clock::duration retry_, retry_max_;
  std::map<std::string, Channel> channels_;
};

}  // namespace afford
