#include "afford/serials.hpp"

#include <algorithm>
#include <cstdint>

namespace afford {

void SerialTracker::expect(const std::string& channel, std::int64_t next) {
  Channel& c = channels_[channel];
  c.expected = next;
  c.evidence = std::max(c.evidence, next);
}

SerialTracker::Verdict SerialTracker::offer(const std::string& channel, std::int64_t serial) {
  Channel& c = channels_[channel];
  if (serial < c.expected) return Verdict::Repeat;
  if (c.final >= 0 && serial >= c.final) return Verdict::Beyond;
  // (a serial of INT64_MAX claims no more than that: 1 + it would overflow)
  c.evidence = std::max(c.evidence, serial == INT64_MAX ? serial : serial + 1);
  if (serial > c.expected) return Verdict::Gap;
  ++c.expected;
  return Verdict::Accept;
}

void SerialTracker::rewind(const std::string& channel, std::int64_t serial) {
  Channel& c = channels_[channel];
  if (serial < c.expected) c.expected = serial;
  c.asked_last = -1;  // ask again at once
}

void SerialTracker::claim(const std::string& channel, std::int64_t count, bool final) {
  Channel& c = channels_[channel];
  count = std::max<std::int64_t>(0, count);
  if (final) {
    c.final = c.final < 0 ? count : std::min(c.final, count);
    count = c.final;
  } else if (c.final >= 0) {
    return;  // a claim from within the run it has left: an old STATUS, or a forged one
  }
  c.claimed = count;
  c.evidence = c.expected;
}

std::int64_t SerialTracker::finalCount(const std::string& channel) const {
  auto it = channels_.find(channel);
  return it == channels_.end() ? -1 : it->second.final;
}

std::vector<SerialTracker::Request> SerialTracker::due(Clock::time_point now,
                                                       const std::function<bool(const std::string&)>& may_ask) {
  std::vector<Request> out;
  for (auto& [name, c] : channels_) {
    if (c.known() <= c.expected) continue;
    // A request stands until its wait is up; once part of it is answered, the rest
    // is due after the short wait, however long the wait had grown.
    const bool progress = c.expected > c.asked_from;
    const bool standing = c.expected <= c.asked_last && now - c.asked_at < (progress ? retry_ : c.wait);
    if (standing) continue;
    if (may_ask && !may_ask(name)) continue;
    // Asked before and nothing came since: the request or its answer was lost, or
    // the publisher is away; wait longer before the next one.
    const bool unanswered = c.asked_last >= 0 && c.expected == c.asked_from && c.expected <= c.asked_last;
    c.wait = unanswered ? std::min(retry_max_, std::max(retry_, c.wait * 2)) : retry_;
    const std::int64_t last = std::min(c.known() - 1, c.expected + batch_ - 1);
    out.push_back({name, c.expected, last});
    c.asked_from = c.expected;
    c.asked_last = last;
    c.asked_at = now;
  }
  return out;
}

SerialTracker::Clock::time_point SerialTracker::nextDue() const {
  Clock::time_point next = Clock::time_point::max();
  for (const auto& [name, c] : channels_)
    if (c.known() > c.expected)
      next = std::min(next, c.expected <= c.asked_last
                                ? c.asked_at + (c.expected > c.asked_from ? retry_ : c.wait)
                                : Clock::time_point{});
  return next;
}

std::int64_t SerialTracker::expected(const std::string& channel) const {
  auto it = channels_.find(channel);
  return it == channels_.end() ? 0 : it->second.expected;
}

std::int64_t SerialTracker::missing() const {
  std::int64_t n = 0;
  for (const auto& [name, c] : channels_) n += std::max<std::int64_t>(0, c.known() - c.expected);
  return n;
}

std::map<std::string, std::pair<std::int64_t, std::int64_t>> SerialTracker::missingRanges() const {
  std::map<std::string, std::pair<std::int64_t, std::int64_t>> out;
  for (const auto& [name, c] : channels_)
    if (c.known() > c.expected) out[name] = {c.expected, c.known()};
  return out;
}

}  // namespace afford
