#include "afford/serials.hpp"

#include <algorithm>

namespace afford {

void SerialTracker::expect(const std::string& channel, std::int64_t next) {
  Channel& c = channels_[channel];
  c.expected = next;
  c.known = std::max(c.known, next);
}

SerialTracker::Verdict SerialTracker::offer(const std::string& channel, std::int64_t serial) {
  Channel& c = channels_[channel];
  if (serial < c.expected) return Verdict::Repeat;
  c.known = std::max(c.known, serial + 1);
  if (serial > c.expected) return Verdict::Gap;
  ++c.expected;
  return Verdict::Accept;
}

void SerialTracker::announce(const std::string& channel, std::int64_t count) {
  Channel& c = channels_[channel];
  c.known = std::max(c.known, count);
}

std::vector<SerialTracker::Request> SerialTracker::due(Clock::time_point now) {
  std::vector<Request> out;
  for (auto& [name, c] : channels_) {
    if (c.known <= c.expected) continue;
    const bool standing = c.expected <= c.asked_last && now - c.asked_at < retry_;
    if (standing) continue;
    const std::int64_t last = std::min(c.known - 1, c.expected + batch_ - 1);
    out.push_back({name, c.expected, last});
    c.asked_last = last;
    c.asked_at = now;
  }
  return out;
}

std::int64_t SerialTracker::expected(const std::string& channel) const {
  auto it = channels_.find(channel);
  return it == channels_.end() ? 0 : it->second.expected;
}

std::int64_t SerialTracker::missing() const {
  std::int64_t n = 0;
  for (const auto& [name, c] : channels_) n += std::max<std::int64_t>(0, c.known - c.expected);
  return n;
}

}  // namespace afford
