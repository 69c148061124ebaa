#include "afford/edge.hpp"

#include <algorithm>
#include <limits>

#include "afford/protocol.hpp"
#include "afford/processes.hpp"

namespace afford {

using Clock = std::chrono::steady_clock;

bool peekRunId(const void* data, std::size_t size, int max_bytes, std::string& out) {
  const auto* p = static_cast<const std::uint8_t*>(data);
  if (size < 12) return false;
  const std::uint32_t len = (std::uint32_t{p[8]} << 24) | (std::uint32_t{p[9]} << 16) | (std::uint32_t{p[10]} << 8) | p[11];
  if (len < 1 || len > static_cast<std::uint32_t>(max_bytes) + 1 || len > size - 12 || p[12 + len - 1] != 0) return false;
  out.assign(reinterpret_cast<const char*>(p + 12), len - 1);
  return true;
}

bool peekRunHeader(const void* data, std::size_t size, RunHeader& out) {
  if (size < 12 || !peekRunId(data, size, static_cast<int>(std::min<std::size_t>(size, INT32_MAX)), out.run_id))
    return false;
  const std::size_t at = 12 + out.run_id.size() + 1;  // the run id's length, its bytes and NUL
  if (at + 16 > size) return false;
  const auto* p = static_cast<const std::uint8_t*>(data) + at;
  std::uint64_t step = 0, serial = 0;
  for (int i = 0; i < 8; ++i) step = (step << 8) | p[i], serial = (serial << 8) | p[8 + i];
  out.step = static_cast<std::int64_t>(step);
  out.serial = static_cast<std::int64_t>(serial);
  return true;
}

Edge::Edge(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, std::string owner, const ProtocolConfig& protocol)
    : lcm_(lcm),
      log_(std::move(log)),
      owner_(std::move(owner)),
      protocol_(&own_protocol_),
      own_protocol_(protocol),
      drop_log_(log_),
      inbound_(log_, own_protocol_,
               {[this](const std::string& channel, const std::string& why) { drop(channel, why); },
                [this](resend_t& m) {
                  m.requester = owner_;
                  send(ch::resend, m);
                }}),
      outbound_(log_, [this](const std::string& channel, const std::vector<std::uint8_t>& bytes) {
        transmit(channel, bytes);
      }) {}

Edge::~Edge() {
  drop_log_.flush();
  for (const auto& s : subs_)
    if (s->sub) lcm_.unsubscribe(s->sub);
}

void Edge::take(const std::string& channel, bool on) {
  bool found = false;
  for (const auto& s : subs_) {
    if (s->channel != channel) continue;
    found = true;
    if (on && !s->sub) {
      s->sub = lcm_.subscribe(channel, &Subscription::on, s.get());
      s->sub->setQueueCapacity(protocol_->queue_capacity);
    } else if (!on && s->sub) {
      lcm_.unsubscribe(s->sub);
      s->sub = nullptr;
    }
  }
  if (!found) throw std::logic_error("Edge::take: " + channel + " is not subscribed");
}

void Edge::join(const std::string& run_id, const RunConfig* config, RequestId request) {
  run_ = run_id;
  request_ = request;
  config_ = config;
  protocol_ = config ? &config->protocol : &own_protocol_;
  inbound_.join(run_id, request, config, *protocol_);
  std::vector<std::string> readers;
  if (config)
    for (const std::string& p : runProcesses(config->phase, config->record))
      if (p != owner_) readers.push_back(p);
  outbound_.join(run_id, request, protocol_->recovery, std::move(readers));
  for (const auto& s : subs_)
    if (s->sub) s->sub->setQueueCapacity(protocol_->queue_capacity);
}

void Edge::leave() {
  drop_log_.flush();
  run_.clear();
  request_ = {};
  config_ = nullptr;
  protocol_ = &own_protocol_;
  inbound_.leave(own_protocol_);
}

bool Edge::inScope(const std::string& channel, const lcm::ReceiveBuffer* rb, const std::string& run_id,
                   Scope scope) {
  if (scope == Scope::Any) return true;
  if (run_.empty()) {
    if (scope == Scope::RunOrAny) return true;
    log_->trace("{}: message of run '{}' ignored: no run joined", channel, run_id);
    return false;
  }
  if (run_id != run_) {
    if (warn_other_runs_)
      refuse(channel, rb, "unknown run id '" + run_id + "' (this process serves run '" + run_ + "')");
    else
      log_->debug("{}: message of run '{}' ignored (serving run '{}')", channel, run_id, run_);
    return false;
  }
  return !(inbound_.failed() && scope == Scope::Run);
}

void Edge::drop(const std::string& channel, const std::string& why) {
  ++drops_.refused;
  drop_log_.drop(channel, why);
}

void Edge::refuse(const std::string& channel, const lcm::ReceiveBuffer* rb, const std::string& why) {
  const KeyMismatch m = key_ ? KeyMismatch::None : keyMismatchOf(nullptr, rb->data, rb->data_size);
  if (m == KeyMismatch::None) return drop(channel, why);
  ++drops_.refused;
  drops_.key.count(m);
  drop_log_.keyMismatch(channel, m);
}

namespace {
// The wall clock, read only for a keyed bus's freshness (a session not heard yet must be recent): never in a
// decision of a run.
std::int64_t nowMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}
}  // namespace

bool Edge::untag(const std::string& channel, const lcm::ReceiveBuffer* rb, std::size_t& size) {
  if (!key_) return true;
  Stamp stamp;
  if (!key_->verify(channel, rb->data, rb->data_size, &stamp)) {
    ++drops_.untagged;
    if (const KeyMismatch m = keyMismatchOf(key_.get(), rb->data, rb->data_size); m != KeyMismatch::None) {
      drops_.key.count(m);
      drop_log_.keyMismatch(channel, m);
    } else {
      drop_log_.drop(channel, "no valid tag of this bus's key (" + std::to_string(rb->data_size) + " bytes)");
    }
    return false;
  }
  if (const std::string why =
          peers_.fresh(stamp, nowMs(), protocol_->freshness_ms, protocol_->limits.peers, drops_.peers_forgotten);
      !why.empty()) {
    ++drops_.replayed;
    drop_log_.drop(channel, why);
    return false;
  }
  size = rb->data_size - BusKey::kTrailerBytes;
  return true;
}

void Edge::transmit(const std::string& channel, const std::vector<std::uint8_t>& bytes) {
  const std::size_t size = bytes.size() + (key_ ? BusKey::kTrailerBytes : 0);
  if (size > static_cast<std::size_t>(protocol_->bus.max_message_bytes))
    throw std::runtime_error(channel + ": a message of " + std::to_string(size) +
                             " bytes is larger than protocol.bus.max_message_bytes (" +
                             std::to_string(protocol_->bus.max_message_bytes) + "): no receiver would take it");
  if (!key_) {
    lcm_.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
    return;
  }
  const std::vector<std::uint8_t> tagged = key_->tagged(channel, bytes.data(), bytes.size(), {session_, sent_++, nowMs()});
  lcm_.publish(channel, tagged.data(), static_cast<unsigned>(tagged.size()));
}

void Edge::answerResends() {
  if (answering_) return;
  answering_ = true;
  subscribe(ch::resend, [this](const resend_t& r) {
    outbound_.answer(r, *protocol_);
    return Turn::take();
  }, Scope::Any, Order::None);
}

}  // namespace afford

namespace afford {

void Edge::save(SnapshotWriter& w) const {
  w.section("taken");
  const std::vector<EdgeInbound::Position> at = inbound_.positions();
  w.i64(static_cast<std::int64_t>(at.size()));
  for (const EdgeInbound::Position& p : at) {
    w.str(p.channel);
    w.i64(p.next);
    w.i64(p.last_digest);
  }
  outbound_.save(w);
}

void Edge::load(SnapshotReader& r) {
  r.section("taken");
  const std::int64_t n = r.within("channels taken", 0, static_cast<std::int64_t>(kChannelCount));
  std::vector<EdgeInbound::Position> at;
  for (std::int64_t i = 0; i < n; ++i) {
    EdgeInbound::Position p;
    p.channel = r.str("channel taken", static_cast<std::size_t>(protocol_->limits.name_bytes));
    if (std::find(inbound_.tracked().begin(), inbound_.tracked().end(), p.channel) == inbound_.tracked().end())
      r.refuse("channel taken", "'" + printable(p.channel, 60) + "' is not a channel this process takes");
    p.next = r.within("next serial", 0, std::numeric_limits<std::int64_t>::max() / 2);
    p.last_digest = r.i64("digest before it");
    at.push_back(p);
  }
  outbound_.load(r, static_cast<std::size_t>(protocol_->bus.max_message_bytes));
  inbound_.restore(at);
}

}  // namespace afford
