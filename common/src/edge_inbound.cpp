#include "afford/edge_inbound.hpp"

#include <algorithm>

#include "afford/processes.hpp"
#include "afford/seal.hpp"

namespace afford {

EdgeInbound::EdgeInbound(std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol, Hooks hooks)
    : log_(std::move(log)),
      protocol_(&protocol),
      hooks_(std::move(hooks)),
      serials_(protocol.resend_batch, std::chrono::milliseconds(protocol.retry_ms),
               std::chrono::milliseconds(protocol.heartbeat_ms)) {}

void EdgeInbound::join(const std::string& run_id, RequestId request, const RunConfig* config,
                       const ProtocolConfig& protocol) {
  run_ = run_id;
  request_ = request;
  stuck_ = {};
  config_ = config;
  protocol_ = &protocol;
  serials_ = SerialTracker(protocol.resend_batch, std::chrono::milliseconds(protocol.retry_ms),
                           std::chrono::milliseconds(protocol.heartbeat_ms));
  deferred_.clear();
  failed_ = false;
  chains_.clear();
  refused_.clear();
  handled_.clear();
  last_activity_ = Clock::now();
}

void EdgeInbound::leave(const ProtocolConfig& protocol) {
  run_.clear();
  request_ = {};
  stuck_ = {};
  config_ = nullptr;
  protocol_ = &protocol;
  deferred_.clear();
  serials_.reset();
  chains_.clear();
  refused_.clear();
  handled_.clear();
  failed_ = false;
}

std::string EdgeInbound::order(const std::string& channel, std::int64_t serial, std::int64_t prev_digest,
                               std::int64_t digest, Order order, bool& skip) {
  skip = false;
  if (serial == serials_.expected(channel) && !follows(channel, serial, prev_digest, order)) {
    const std::string why = "field prev_digest does not follow " +
                            (serial == 0 ? std::string("the start of the request's chain")
                                         : "the channel's message " + std::to_string(serial - 1)) +
                            " (a copy given another serial, or another request's)";
    stuckOn(channel, serial, why);
    return why;
  }
  switch (serials_.offer(channel, serial)) {
    case SerialTracker::Verdict::Repeat:
      log_->trace("{}: serial {} already had (a repeat)", channel, serial);
      skip = true;
      return "";
    case SerialTracker::Verdict::Gap:
      if (order == Order::Follow) {  // an observer goes on from here
        serials_.expect(channel, serial);
        serials_.offer(channel, serial);
        break;
      }
      log_->debug("{}: serial {} came before serial {}: asking for the missing ones", channel, serial,
                  serials_.expected(channel));
      askMissing();
      skip = true;
      return "";
    case SerialTracker::Verdict::Beyond:
      return "field serial = " + std::to_string(serial) + " is at or beyond the " +
             std::to_string(serials_.finalCount(channel)) +
             " messages its publisher published in the run before it left";
    case SerialTracker::Verdict::Accept:
      break;
  }
  chained(channel, serial, digest);
  return "";
}

bool EdgeInbound::blocked(const std::string& channel) const {
  return std::any_of(deferred_.begin(), deferred_.end(), [&](const Pending& p) { return p.channel == channel; });
}

Turn::Kind EdgeInbound::attempt(Pending& p) {
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
    if (p.serial >= 0) handled(p);
    if (p.serial >= 0) stuck_ = {};
    last_activity_ = Clock::now();
    if (answered) {
      usual_wait_ += (came - published - usual_wait_) / 8;
      awaiting_ = last_published_ > came;  // the handler published: a new wait begins
    }
  }
  if (t.kind() == Turn::Kind::Refuse) refused(p, t.why());
  return t.kind();
}

void EdgeInbound::expectSerial(const std::string& channel, std::int64_t next, std::int64_t last_digest) {
  serials_.expect(channel, next);
  Chain& c = chains_[channel];
  c.first = next - 1;
  c.digests.assign(1, last_digest);
  handled_[channel] = {next, last_digest};
}

void EdgeInbound::handled(const Pending& p) {
  handled_[p.channel] = {p.serial + 1, p.digest};
  // The chain is needed from the digest before the next message to handle on (a message accepted after it
  // may still be refused, and its serial expected again): what came before goes.
  Chain& c = chains_[p.channel];
  if (!c.knows(p.serial) || p.serial == c.first) return;
  c.digests.erase(c.digests.begin(), c.digests.begin() + static_cast<std::ptrdiff_t>(p.serial - c.first));
  c.first = p.serial;
}

std::vector<EdgeInbound::Position> EdgeInbound::positions() const {
  std::vector<Position> out;
  for (const std::string& ch : tracked_) {
    const auto it = handled_.find(ch);
    if (it == handled_.end())
      out.push_back({ch, 0, chainSeed(run_, ch, request_.number)});
    else
      out.push_back({ch, it->second.first, it->second.second});
  }
  return out;
}

void EdgeInbound::restore(const std::vector<Position>& at) {
  for (const Position& p : at)
    if (p.next > 0) expectSerial(p.channel, p.next, p.last_digest);
}

bool EdgeInbound::follows(const std::string& channel, std::int64_t serial, std::int64_t prev_digest, Order order) {
  if (serial == 0) return prev_digest == chainSeed(run_, channel, request_.number);
  const Chain& c = chains_[channel];
  if (!c.knows(serial - 1)) return order == Order::Follow;  // an observer that came in later takes what it gets
  return prev_digest == c.digests[static_cast<std::size_t>(serial - 1 - c.first)];
}

void EdgeInbound::chained(const std::string& channel, std::int64_t serial, std::int64_t digest) {
  Chain& c = chains_[channel];
  if (!c.knows(serial - 1)) {  // the first one known (serial 0, or an observer's first)
    c.first = serial;
    c.digests.clear();
  }
  c.digests.resize(static_cast<std::size_t>(serial - c.first));
  c.digests.push_back(digest);
}

void EdgeInbound::refused(const Pending& p, const std::string& why) {
  // Not the channel's next message after all (a forged or mangled one that
  // passed every check): drop it and whatever waits behind it on its channel,
  // and expect that serial again.
  const auto again = refused_.find(p.channel);
  if (again != refused_.end() && again->second == std::make_pair(p.serial, p.digest))
    return fail(p.channel, "serial " + std::to_string(p.serial) + " was refused (" + why +
                               "), asked for again, and refused again: its handler refuses the channel's next "
                               "message itself, so the run cannot go on");
  refused_[p.channel] = {p.serial, p.digest};
  stuckOn(p.channel, p.serial, why);
  hooks_.drop(p.channel, why);
  deferred_.erase(std::remove_if(deferred_.begin(), deferred_.end(),
                                 [&](const Pending& d) { return d.channel == p.channel && d.serial > p.serial; }),
                  deferred_.end());
  serials_.rewind(p.channel, p.serial);
  Chain& c = chains_[p.channel];
  if (c.knows(p.serial)) c.digests.resize(static_cast<std::size_t>(p.serial - c.first));
}

void EdgeInbound::dispatch(Pending p) {
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

void EdgeInbound::retryDeferred() {
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

void EdgeInbound::stuckOn(const std::string& channel, std::int64_t serial, const std::string& why) {
  if (stuck_.channel == channel && stuck_.serial == serial && stuck_.why == why) {
    ++stuck_.times;
    return;
  }
  stuck_ = {channel, why, serial, 1};
}

std::string EdgeInbound::stuck() const {
  if (stuck_.channel.empty()) return "";
  const Phase phase = config_ ? config_->phase : Phase::Intrinsic;
  const std::string publisher = publisherOf(stuck_.channel, phase);
  return stuck_.channel + " serial " + std::to_string(stuck_.serial) +
         (publisher.empty() ? "" : " (published by " + publisher + ")") + ": " + stuck_.why + ", " +
         std::to_string(stuck_.times) + (stuck_.times == 1 ? " time" : " times");
}

void EdgeInbound::fail(const std::string& channel, const std::string& why) {
  if (failed_) return log_->debug("{}: {} (after the failure)", channel, why);
  failed_ = true;
  deferred_.clear();
  if (!on_failure_) return log_->error("{}: {}", channel, why);
  on_failure_(channel, why);  // (which says it: once)
}

void EdgeInbound::claim(const process_status_t& st) {
  if (run_.empty() || st.counts_run != run_ || st.counts_config != request_.config_digest) return;  // another request's counts
  // It has left the request: its counts are final.
  const bool left = st.run_id != st.counts_run || st.config_digest != st.counts_config;
  const Phase phase = config_ ? config_->phase : Phase::Intrinsic;
  bool any = false;
  for (int i = 0; i < st.n_channels; ++i) {
    const std::string& ch = st.channels[i];
    if (std::find(tracked_.begin(), tracked_.end(), ch) == tracked_.end()) continue;
    if (publisherOf(ch, phase) != st.process) continue;  // only a channel's publisher speaks for it
    serials_.claim(ch, st.counts[i], /*final=*/left);
    any = true;
    const std::int64_t expected = serials_.expected(ch);
    if (i < static_cast<int>(st.held_from.size()) && st.held_from[i] > expected && st.held_from[i] <= st.counts[i])
      return fail(ch, "serials " + std::to_string(expected) + ".." + std::to_string(st.held_from[i] - 1) +
                          " are no longer held by its publisher (" + st.process + " holds it from serial " +
                          std::to_string(st.held_from[i]) +
                          "): it let them go once every reader had a later snapshot, so this process cannot catch "
                          "up without its own latest snapshot (docs/operating.md, \"Killing and restarting a process\")");
  }
  if (any) askMissing();
}

void EdgeInbound::askMissing() {
  if (run_.empty() || failed_) return;
  const auto may_ask = [this](const std::string& ch) {
    // A channel whose messages wait for another channel's asks for no more meanwhile.
    const auto waiting = std::count_if(deferred_.begin(), deferred_.end(), [&](const Pending& p) { return p.channel == ch; });
    return waiting < protocol_->resend_batch;
  };
  for (const SerialTracker::Request& r : serials_.due(Clock::now(), may_ask)) {
    log_->debug("{}: asking for serials {}..{}", r.channel, r.first, r.last);
    resend_t m{};
    m.run_id = run_;
    m.step = 0;
    m.config_digest = request_.config_digest;
    m.channel = r.channel;
    m.first = r.first;
    m.last = r.last;
    hooks_.ask(m);
  }
}

}  // namespace afford
