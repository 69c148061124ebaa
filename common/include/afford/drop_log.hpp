// What an edge says of the messages it drops (docs/processes-and-channels.md,
// "The message edge"). Every drop is counted by kind (its channel and its
// reason, numbers aside); the first few drops of each kind are said one line
// each, the others only in summaries: one when a drop comes at least a delay
// after the last line (the delay doubles from 1 s up to 10 min while drops go
// on), and one when the owner leaves its run or ends. A flood of bad messages
// costs a few dozen lines, not one a message (a replayed recording used to
// write tens of thousands). A message dropped because the owner's key, or its
// lack of one, does not fit the bus (afford/auth.hpp) is one line naming the
// fix, once in the owner's life, and only counts after it.
#pragma once
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <string>

#include "afford/auth.hpp"

namespace afford {

class DropLog {
 public:
  using Clock = std::chrono::steady_clock;
  static constexpr int kSaidPerKind = 3;      // drops of one kind said one line each
  static constexpr int kSaidAtMost = 20;      // ... and of all kinds, until the next flush()
  static constexpr int kKinds = 64;           // kinds told apart in a summary (the rest: "other")
  static constexpr std::chrono::seconds kFirstDelay{1}, kLongestDelay{600};

  explicit DropLog(std::shared_ptr<spdlog::logger> log) : log_(std::move(log)) {}
  // A message dropped on `channel` for `why`.
  void drop(const std::string& channel, const std::string& why);
  // A message on `channel` dropped because the key does not fit (m is not None): its kind's hint once, then counts.
  void keyMismatch(const std::string& channel, KeyMismatch m);
  // Say what was not said yet in one line, and start afresh (the owner leaves its run, or ends).
  void flush();
  std::int64_t unsaid() const { return unsaid_; }  // drops counted since the last line that told of them

 private:
  struct Kind {
    std::string example;      // the first such reason, as it was
    std::int64_t said = 0;    // said one line each
    std::int64_t unsaid = 0;  // since the last summary
  };
  void summarise(const char* when);
  Kind& kind(const std::string& key, const std::string& example);  // (beyond kKinds: "other")
  void unsaid(Kind& k, Clock::time_point now);                      // counted for the next summary

  std::shared_ptr<spdlog::logger> log_;
  std::map<std::string, Kind> kinds_;  // by channel and reason with its numbers taken out
  int said_ = 0;                       // lines said one a drop, since the last flush
  std::int64_t unsaid_ = 0;
  std::set<KeyMismatch> hinted_;  // the key hints said (never again: flush() keeps them)
  Clock::time_point last_line_{}, first_unsaid_{};
  Clock::duration delay_ = kFirstDelay;
};

}  // namespace afford
