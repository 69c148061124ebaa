// Reliable delivery over lossy multicast, by serial numbers.
//
// Every run message carries `serial`: its publisher's count of the messages it
// published earlier on that channel in the run. A receiver takes each channel
// strictly in serial order: a serial it has had is a repeat (dropped quietly);
// a serial beyond the next one means something was lost, and the receiver
// asks the publisher (RESEND) for the missing ones. Publishers announce how
// many messages they have published on each channel in their STATUS
// heartbeat, so a receiver also notices a lost last message, and a restarted
// receiver pulls the whole run it missed. The wall clock paces the requests
// only; it never decides what a process does with a message.
#pragma once
#include <chrono>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace afford {

class SerialTracker {
 public:
  using Clock = std::chrono::steady_clock;
  enum class Verdict { Accept, Repeat, Gap };
  struct Request {
    std::string channel;
    std::int64_t first = 0, last = 0;  // inclusive
  };

  // `batch`: most messages asked for at once; `retry`: how long an unanswered
  // request stands before it is asked again.
  explicit SerialTracker(std::int64_t batch = 64, Clock::duration retry = std::chrono::milliseconds(300))
      : batch_(batch), retry_(retry) {}

  void reset() { channels_.clear(); }
  // Start expecting `channel` at serial `next` (a restarted logger resumes its log).
  void expect(const std::string& channel, std::int64_t next);
  // A message arrived: Accept advances the channel's expected serial.
  Verdict offer(const std::string& channel, std::int64_t serial);
  // The publisher says it has published `count` messages on `channel`.
  void announce(const std::string& channel, std::int64_t count);
  // Requests due now: each channel behind its known count, at most `batch`
  // messages, not again while an earlier request stands.
  std::vector<Request> due(Clock::time_point now);
  std::int64_t expected(const std::string& channel) const;
  std::int64_t missing() const;  // messages known to exist and not yet had, all channels

 private:
  struct Channel {
    std::int64_t expected = 0;   // the next serial to accept
    std::int64_t known = 0;      // messages known to exist
    std::int64_t asked_last = -1;
    Clock::time_point asked_at{};
  };
  std::int64_t batch_;
  Clock::duration retry_;
  std::map<std::string, Channel> channels_;
};

}  // namespace afford
