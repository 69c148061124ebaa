#include "afford/edge_outbound.hpp"

#include <algorithm>
#include <limits>

#include "afford/seal.hpp"
#include "afford/snapshot.hpp"

namespace afford {

EdgeOutbound::EdgeOutbound(std::shared_ptr<spdlog::logger> log, Transmit transmit)
    : log_(std::move(log)), transmit_(std::move(transmit)) {}

void EdgeOutbound::join(const std::string& run_id, RequestId request, const RecoveryConfig& recovery,
                        std::vector<std::string> readers) {
  run_ = run_id;
  request_ = request;
  recovery_ = recovery;
  history_.clear();
  bytes_ = 0;
  over_bound_ = 0;
  readers_ = std::set<std::string>(readers.begin(), readers.end());
  from_.clear();
}

std::int64_t EdgeOutbound::nextSerial(const std::string& channel) const {
  const auto it = history_.find(channel);
  return it == history_.end() ? 0 : it->second.count();
}

std::int64_t EdgeOutbound::lastDigest(const std::string& channel) const {
  const auto it = history_.find(channel);
  return it == history_.end() || it->second.count() == 0 ? chainSeed(run_, channel, request_.number) : it->second.last_digest;
}

void EdgeOutbound::kept(const std::string& channel, std::int64_t digest, std::vector<std::uint8_t> bytes) {
  History& h = history_[channel];
  h.last_digest = digest;
  h.bytes += bytes.size();
  bytes_ += bytes.size();
  h.messages.push_back(std::move(bytes));
  h.republished.emplace_back();
  if (hold_nothing_) popFront(h);
  letGo();
  bound();
}

void EdgeOutbound::popFront(History& h) {
  h.bytes -= h.messages.front().size();
  bytes_ -= h.messages.front().size();
  h.messages.pop_front();
  h.republished.pop_front();
  ++h.first;
}

void EdgeOutbound::readerSaid(const process_status_t& st) {
  if (run_.empty() || st.run_id != run_ || st.config_digest != request_.config_digest || !readers_.count(st.process)) return;
  auto& at = from_[st.process];
  at.clear();
  for (int i = 0; i < st.n_takes; ++i) at[st.takes[i]] = st.takes_from[i];
  letGo();
}

void EdgeOutbound::letGo() {
  if (recovery_.snapshot_steps <= 0) return;  // nobody takes snapshots: a restart replays the whole run
  if (from_.size() < readers_.size()) return;  // a process of the run not heard yet may take any channel
  for (auto& [channel, h] : history_) {
    std::int64_t floor = h.count() - recovery_.history_keep;
    for (const auto& [reader, at] : from_) {
      const auto it = at.find(channel);
      if (it != at.end()) floor = std::min(floor, it->second);
    }
    while (h.first < floor && !h.messages.empty()) popFront(h);
  }
}

void EdgeOutbound::bound() {
  if (recovery_.history_mb <= 0) return;
  const std::size_t most = static_cast<std::size_t>(recovery_.history_mb) << 20;
  while (bytes_ > most) {
    auto largest = std::max_element(history_.begin(), history_.end(),
                                    [](const auto& a, const auto& b) { return a.second.bytes < b.second.bytes; });
    if (largest == history_.end() || largest->second.messages.size() <= 1) return;  // the last message stays
    popFront(largest->second);
    ++over_bound_;
    if (over_bound_ == 1)
      log_->warn("{}: what this process holds of what it published reached protocol.recovery.history_mb ({} MiB): "
                 "the oldest is let go even where a reader's restart would need it",
                 largest->first, recovery_.history_mb);
  }
}

void EdgeOutbound::answer(const resend_t& r, const ProtocolConfig& protocol) {
  if (r.run_id.empty() || r.run_id != run_ || r.config_digest != request_.config_digest) return;
  auto it = history_.find(r.channel);
  if (it == history_.end()) return;  // another publisher's channel
  History& h = it->second;
  const std::int64_t n = h.count();
  const std::int64_t first = std::max<std::int64_t>(h.first, r.first);
  if (first >= n) return;  // nothing published there (also keeps the sum below from overflowing)
  if (r.first < h.first)
    log_->debug("{}: serials {}..{} asked by {} were let go (held from {})", r.channel, r.first,
                std::min(r.last, h.first - 1), r.requester, h.first);
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
    auto& at = h.republished[static_cast<std::size_t>(i - h.first)];
    if (at != Clock::time_point{} && now - at < retry / 2) {  // just republished: that copy serves this request too
      ++held;
      continue;
    }
    if (h.in_window >= protocol.resend_budget) break;  // a storm of requests costs at most the budget
    transmit_(r.channel, h.messages[static_cast<std::size_t>(i - h.first)]);
    at = now;
    ++h.in_window;
    ++sent;
  }
  log_->debug("{}: serials {}..{} asked by {}: {} republished, {} just were", r.channel, first, last, r.requester, sent,
              held);
}

std::vector<EdgeOutbound::Count> EdgeOutbound::counts() const {
  std::vector<Count> out;
  for (const auto& [channel, h] : history_) out.push_back({channel, h.count(), h.first});
  return out;
}

void EdgeOutbound::save(SnapshotWriter& w) const {
  w.section("published");
  w.i64(static_cast<std::int64_t>(history_.size()));
  for (const auto& [channel, h] : history_) {
    w.str(channel);
    w.i64(h.first);
    w.i64(h.last_digest);
    w.i64(static_cast<std::int64_t>(h.messages.size()));
    for (const auto& m : h.messages) w.blob(m);
  }
}

void EdgeOutbound::load(SnapshotReader& r, std::size_t max_message_bytes) {
  r.section("published");
  history_.clear();
  bytes_ = 0;
  const std::int64_t channels = r.within("published channels", 0, 1024);
  for (std::int64_t c = 0; c < channels; ++c) {
    const std::string channel = r.str("published channel", 256);
    History& h = history_[channel];
    h.first = r.within("first held serial", 0, std::numeric_limits<std::int64_t>::max() / 2);
    h.last_digest = r.i64("last digest");
    const std::int64_t n = r.within("messages held", 0, std::numeric_limits<std::int32_t>::max());
    for (std::int64_t i = 0; i < n; ++i) {
      h.messages.push_back(r.blob("message held", max_message_bytes));
      h.republished.emplace_back();
      h.bytes += h.messages.back().size();
    }
    bytes_ += h.bytes;
  }
}

}  // namespace afford
