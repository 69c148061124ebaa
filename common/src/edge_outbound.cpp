#include "afford/edge_outbound.hpp"

#include <algorithm>

#include "afford/seal.hpp"

namespace afford {

EdgeOutbound::EdgeOutbound(std::shared_ptr<spdlog::logger> log, Transmit transmit)
    : log_(std::move(log)), transmit_(std::move(transmit)) {}

void EdgeOutbound::join(const std::string& run_id) {
  run_ = run_id;
  history_.clear();
}

std::int64_t EdgeOutbound::nextSerial(const std::string& channel) const {
  const auto it = history_.find(channel);
  return it == history_.end() ? 0 : static_cast<std::int64_t>(it->second.messages.size());
}

std::int64_t EdgeOutbound::lastDigest(const std::string& channel) const {
  const auto it = history_.find(channel);
  return it == history_.end() || it->second.messages.empty() ? chainSeed(run_, channel) : it->second.last_digest;
}

void EdgeOutbound::kept(const std::string& channel, std::int64_t digest, std::vector<std::uint8_t> bytes) {
  History& h = history_[channel];
  h.last_digest = digest;
  h.messages.push_back(std::move(bytes));
  h.republished.emplace_back();
}

void EdgeOutbound::answer(const resend_t& r, const ProtocolConfig& protocol) {
  if (r.run_id.empty() || r.run_id != run_) return;
  auto it = history_.find(r.channel);
  if (it == history_.end()) return;  // another publisher's channel
  History& h = it->second;
  const auto n = static_cast<std::int64_t>(h.messages.size());
  const std::int64_t first = std::max<std::int64_t>(0, r.first);
  if (first >= n) return;  // nothing published there (also keeps the sum below from overflowing)
  const std::int64_t last = std::min({r.last, first + protocol.resend_cap - 1, n - 1});
  if (first > last) return;
  const auto now = Clock::now();
  const auto retry = std::chrono::milliseconds(protocol.retry_ms);
  if (now - h.window >= retry) {
    h.window = now;
    h.in_window = 0;
  }
  int sent = 0, held = 0;
  for (std::int64_t i = first; i <= last; ++i) {
    auto& at = h.republished[static_cast<std::size_t>(i)];
    if (at != Clock::time_point{} && now - at < retry / 2) {  // just republished: that copy serves this request too
      ++held;
      continue;
    }
    if (h.in_window >= protocol.resend_budget) break;  // a storm of requests costs at most the budget
    transmit_(r.channel, h.messages[static_cast<std::size_t>(i)]);
    at = now;
    ++h.in_window;
    ++sent;
  }
  log_->debug("{}: serials {}..{} asked by {}: {} republished, {} just were", r.channel, first, last, r.requester, sent,
              held);
}

std::vector<std::pair<std::string, std::int64_t>> EdgeOutbound::counts() const {
  std::vector<std::pair<std::string, std::int64_t>> out;
  for (const auto& [channel, h] : history_) out.emplace_back(channel, static_cast<std::int64_t>(h.messages.size()));
  return out;
}

}  // namespace afford
