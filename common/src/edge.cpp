#include "afford/edge.hpp"

#include <algorithm>

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
      serials_(protocol.resend_batch, std::chrono::milliseconds(protocol.retry_ms),
               std::chrono::milliseconds(protocol.heartbeat_ms)) {}

Edge::~Edge() {
  for (const auto& s : subs_) lcm_.unsubscribe(s->sub);
}

void Edge::join(const std::string& run_id, const RunConfig* config) {
  run_ = run_id;
  config_ = config;
  protocol_ = config ? &config->protocol : &own_protocol_;
  serials_ = SerialTracker(protocol_->resend_batch, std::chrono::milliseconds(protocol_->retry_ms),
                           std::chrono::milliseconds(protocol_->heartbeat_ms));
  deferred_.clear();
  failed_ = false;
  chains_.clear();
  refused_.clear();
  history_.clear();
  history_run_ = run_id;
  last_activity_ = Clock::now();
  for (const auto& s : subs_) s->sub->setQueueCapacity(protocol_->queue_capacity);
}

void Edge::leave() {
  run_.clear();
  config_ = nullptr;
  protocol_ = &own_protocol_;
  deferred_.clear();
  serials_.reset();
  chains_.clear();
  refused_.clear();
  failed_ = false;
}

bool Edge::inScope(const std::string& channel, const std::string& run_id, Scope scope) {
  if (scope == Scope::Any) return true;
  if (run_.empty()) {
    if (scope == Scope::RunOrAny) return true;
    log_->trace("{}: message of run '{}' ignored: no run joined", channel, run_id);
    return false;
  }
  if (run_id != run_) {
    if (warn_other_runs_)
      drop(channel, "unknown run id '" + run_id + "' (this process serves run '" + run_ + "')");
    else
      log_->debug("{}: message of run '{}' ignored (serving run '{}')", channel, run_id, run_);
    return false;
  }
  return !(failed_ && scope == Scope::Run);
}

void Edge::drop(const std::string& channel, const std::string& why) {
  ++drops_.refused;
  log_->warn("{}: dropped message: {}", channel, why);
}

bool Edge::untag(const std::string& channel, const lcm::ReceiveBuffer* rb, std::size_t& size) {
  if (!key_) return true;
  if (!key_->verify(channel, rb->data, rb->data_size)) {
    ++drops_.untagged;
    log_->warn("{}: dropped message: no valid tag of this bus's key ({} bytes)", channel, rb->data_size);
    return false;
  }
  size = rb->data_size - BusKey::kTagBytes;
  return true;
}

void Edge::transmit(const std::string& channel, const std::vector<std::uint8_t>& bytes) {
  const std::size_t size = bytes.size() + (key_ ? BusKey::kTagBytes : 0);
  if (size > static_cast<std::size_t>(protocol_->bus.max_message_bytes))
    throw std::runtime_error(channel + ": a message of " + std::to_string(size) +
                             " bytes is larger than protocol.bus.max_message_bytes (" +
                             std::to_string(protocol_->bus.max_message_bytes) + "): no receiver would take it");
  if (!key_) {
    lcm_.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
    return;
  }
  const std::vector<std::uint8_t> tagged = key_->tagged(channel, bytes.data(), bytes.size());
  lcm_.publish(channel, tagged.data(), static_cast<unsigned>(tagged.size()));
}

bool Edge::blocked(const std::string& channel) const {
  return std::any_of(deferred_.begin(), deferred_.end(), [&](const Pending& p) { return p.channel == channel; });
}

Turn::Kind Edge::attempt(Pending& p) {
  // Waiting for an input since our last publication, if this message is taken (before its handler, which may
  // publish again).
  const bool answered = awaiting_ && p.serial >= 0;  // a run message: a peer's STATUS says nothing of the pace
  const Clock::time_point came = Clock::now(), published = last_published_;
  Turn t = Turn::take();
  try {
    t = p.call();
  } catch (const std::exception& e) {
    fail(p.channel, e.what());
    return Turn::Kind::Refuse;
  } catch (...) {
    fail(p.channel, "an unknown exception");
    return Turn::Kind::Refuse;
  }
  if (t.kind() == Turn::Kind::Take) {
    last_activity_ = Clock::now();
    if (answered) {
      usual_wait_ += (came - published - usual_wait_) / 8;
      awaiting_ = last_published_ > came;  // the handler published: a new wait begins
    }
  }
  if (t.kind() == Turn::Kind::Refuse) refused(p, t.why());
  return t.kind();
}

void Edge::expectSerial(const std::string& channel, std::int64_t next, std::int64_t last_digest) {
  serials_.expect(channel, next);
  Chain& c = chains_[channel];
  c.first = next - 1;
  c.digests.assign(1, last_digest);
}

bool Edge::follows(const std::string& channel, std::int64_t serial, std::int64_t prev_digest, Order order) {
  if (serial == 0) return prev_digest == chainSeed(run_, channel);
  const Chain& c = chains_[channel];
  if (!c.knows(serial - 1)) return order == Order::Follow;  // an observer that came in later takes what it gets
  return prev_digest == c.digests[static_cast<std::size_t>(serial - 1 - c.first)];
}

void Edge::chained(const std::string& channel, std::int64_t serial, std::int64_t digest) {
  Chain& c = chains_[channel];
  if (!c.knows(serial - 1)) {  // the first one known (serial 0, or an observer's first)
    c.first = serial;
    c.digests.clear();
  }
  c.digests.resize(static_cast<std::size_t>(serial - c.first));
  c.digests.push_back(digest);
}

void Edge::refused(const Pending& p, const std::string& why) {
  // Not the channel's next message after all (a forged or mangled one that
  // passed every check): drop it and whatever waits behind it on its channel,
  // and expect that serial again.
  const auto again = refused_.find(p.channel);
  if (again != refused_.end() && again->second == std::make_pair(p.serial, p.digest))
    return fail(p.channel, "serial " + std::to_string(p.serial) + " was refused (" + why +
                               "), asked for again, and refused again: its handler refuses the channel's next "
                               "message itself, so the run cannot go on");
  refused_[p.channel] = {p.serial, p.digest};
  drop(p.channel, why);
  deferred_.erase(std::remove_if(deferred_.begin(), deferred_.end(),
                                 [&](const Pending& d) { return d.channel == p.channel && d.serial > p.serial; }),
                  deferred_.end());
  serials_.rewind(p.channel, p.serial);
  Chain& c = chains_[p.channel];
  if (c.knows(p.serial)) c.digests.resize(static_cast<std::size_t>(p.serial - c.first));
}

void Edge::dispatch(Pending p) {
  if (failed_) return;
  if (!blocked(p.channel)) {
    switch (attempt(p)) {
      case Turn::Kind::Take:
        return retryDeferred();
      case Turn::Kind::Refuse:
        return;
      case Turn::Kind::Later:
        break;
    }
  }
  if (failed_) return;
  if (static_cast<int>(deferred_.size()) >= protocol_->max_deferred)
    return fail(p.channel, std::to_string(deferred_.size()) +
                               " messages wait for their turn (protocol.max_deferred): the message of another "
                               "channel they wait for does not come");
  deferred_.push_back(std::move(p));
}

void Edge::retryDeferred() {
  if (retrying_ || deferred_.empty()) return;
  retrying_ = true;
  for (bool progress = true; progress && !deferred_.empty() && !failed_;) {
    progress = false;
    std::deque<Pending> waiting;
    waiting.swap(deferred_);
    std::vector<std::string> stuck;  // channels whose earlier message still waits
    while (!waiting.empty() && !failed_) {
      Pending p = std::move(waiting.front());
      waiting.pop_front();
      if (std::find(stuck.begin(), stuck.end(), p.channel) != stuck.end()) {
        deferred_.push_back(std::move(p));
        continue;
      }
      switch (attempt(p)) {
        case Turn::Kind::Take:
          progress = true;
          break;
        case Turn::Kind::Later:
          stuck.push_back(p.channel);
          deferred_.push_back(std::move(p));
          break;
        case Turn::Kind::Refuse:  // its channel's later messages go too (refused() dropped those deferred)
          waiting.erase(std::remove_if(waiting.begin(), waiting.end(),
                                       [&](const Pending& d) { return d.channel == p.channel; }),
                        waiting.end());
          progress = true;
          break;
      }
    }
    if (failed_) deferred_.clear();
  }
  retrying_ = false;
}

void Edge::fail(const std::string& channel, const std::string& why) {
  if (failed_) return log_->debug("{}: {} (after the failure)", channel, why);
  failed_ = true;
  deferred_.clear();
  log_->error("{}: {}", channel, why);
  if (on_failure_) on_failure_(channel, why);
}

void Edge::claim(const process_status_t& st) {
  if (run_.empty() || st.counts_run != run_) return;
  const bool extrinsic = config_ && config_->phase == Phase::Extrinsic;
  bool any = false;
  for (int i = 0; i < st.n_channels; ++i) {
    const std::string& ch = st.channels[i];
    if (std::find(tracked_.begin(), tracked_.end(), ch) == tracked_.end()) continue;
    if (publisherOf(ch, extrinsic) != st.process) continue;  // only a channel's publisher speaks for it
    serials_.claim(ch, st.counts[i], /*final=*/st.run_id != st.counts_run);  // it has left the run
    any = true;
  }
  if (any) askMissing();
}

void Edge::askMissing() {
  if (run_.empty() || failed_) return;
  const auto may_ask = [this](const std::string& ch) {
    // A channel whose messages wait for another channel's asks for no more meanwhile.
    const auto waiting = std::count_if(deferred_.begin(), deferred_.end(), [&](const Pending& p) { return p.channel == ch; });
    return waiting < protocol_->resend_batch;
  };
  for (const SerialTracker::Request& r : serials_.due(Clock::now(), may_ask)) {
    log_->debug("{}: asking for serials {}..{}", r.channel, r.first, r.last);
    resend_t m;
    m.run_id = run_;
    m.step = 0;
    m.channel = r.channel;
    m.first = r.first;
    m.last = r.last;
    m.requester = owner_;
    send(ch::resend, m);
  }
}

void Edge::answerResends() {
  if (answering_) return;
  answering_ = true;
  subscribe(ch::resend, [this](const resend_t& r) {
    onResend(r);
    return Turn::take();
  }, Scope::Any, Order::None);
}

void Edge::onResend(const resend_t& r) {
  if (r.run_id.empty() || r.run_id != history_run_) return;
  auto it = history_.find(r.channel);
  if (it == history_.end()) return;  // another publisher's channel
  History& h = it->second;
  const auto n = static_cast<std::int64_t>(h.messages.size());
  const std::int64_t first = std::max<std::int64_t>(0, r.first);
  if (first >= n) return;  // nothing published there (also keeps the sum below from overflowing)
  const std::int64_t last = std::min({r.last, first + protocol_->resend_cap - 1, n - 1});
  if (first > last) return;
  const auto now = Clock::now();
  const auto retry = std::chrono::milliseconds(protocol_->retry_ms);
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
    if (h.in_window >= protocol_->resend_budget) break;  // a storm of requests costs at most the budget
    transmit(r.channel, h.messages[static_cast<std::size_t>(i)]);
    at = now;
    ++h.in_window;
    ++sent;
  }
  log_->debug("{}: serials {}..{} asked by {}: {} republished, {} just were", r.channel, first, last, r.requester, sent,
              held);
}

bool Edge::newerStatus(const process_status_t& st) {
  const std::string key = st.process + "#" + std::to_string(st.pid);
  auto it = beats_.find(key);
  if (it != beats_.end()) {
    if (st.beat <= it->second.beat) return false;
    it->second = {st.beat, ++beat_order_};
    return true;
  }
  // Forged pids cannot grow it further: the one heard from longest ago is forgotten.
  if (beats_.size() >= static_cast<std::size_t>(protocol_->limits.peers)) {
    beats_.erase(std::min_element(beats_.begin(), beats_.end(),
                                  [](const auto& a, const auto& b) { return a.second.order < b.second.order; }));
    ++drops_.peers_forgotten;
  }
  beats_[key] = {st.beat, ++beat_order_};
  return true;
}

std::vector<std::pair<std::string, std::int64_t>> Edge::counts() const {
  std::vector<std::pair<std::string, std::int64_t>> out;
  for (const auto& [channel, h] : history_) out.emplace_back(channel, static_cast<std::int64_t>(h.messages.size()));
  return out;
}

}  // namespace afford
