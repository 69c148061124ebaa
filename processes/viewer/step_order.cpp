#include "viewer/step_order.hpp"

#include <algorithm>
#include <stdexcept>

#include "afford/config.hpp"
#include "afford/decode.hpp"
#include "afford/edge.hpp"
#include "afford/protocol.hpp"
#include "afford/seal.hpp"

namespace afford {

int stepRank(const std::string& channel) {
  static const char* const order[] = {ch::runConfig.name,       ch::runControl.name,  ch::probe.name,
                                      ch::scene.name,           ch::effect.name,      ch::goalResult.name,
                                      ch::goal.name,            ch::look.name,        ch::focus.name,
                                      ch::affordanceTable.name, ch::prediction.name,  ch::forwardQuery.name,
                                      ch::forwardPrediction.name, ch::decision.name,  ch::extrinsicResult.name,
                                      ch::result.name,          ch::status.name};
  const int n = static_cast<int>(std::size(order));
  for (int i = 0; i < n; ++i)
    if (channel == order[i]) return i;
  return n;  // RESEND, and channels the protocol does not have
}

std::optional<StepKey> stepKeyOf(const LogEvent& e, Phase phase, const BoundsContext& ctx) {
  const int rank = stepRank(e.channel);
  if (e.channel == ch::runConfig.name) return StepKey{StepKey::kBefore, rank};
  if (!sealIntact(e.data.data(), e.data.size())) return std::nullopt;
  std::string why;
  if (e.channel == ch::runControl.name) {
    run_control_t m{};
    if (!decodeChecked(e.data.data(), e.data.size(), ctx, m, why)) return std::nullopt;
    return StepKey{m.command == run_control_t::START ? StepKey::kBefore : StepKey::kAfter, rank};
  }
  if (e.channel == ch::status.name) {
    process_status_t m{};
    if (!decodeChecked(e.data.data(), e.data.size(), ctx, m, why)) return std::nullopt;
    return StepKey{m.step, rank};
  }
  RunHeader h;
  if (!isSerialChannel(e.channel) || !peekRunHeader(e.data.data(), e.data.size(), h)) return std::nullopt;
  // An action's effect is seen on the scene of the step after it (intrinsic and goals phases: that scene has the
  // next step; in the extrinsic phase the action's scene has the action's step).
  if (e.channel == ch::effect.name && phase != Phase::Extrinsic && h.step < StepKey::kAfter) ++h.step;
  return StepKey{h.step, rank};
}

void StepTrail::add(std::int64_t step) {
  std::int64_t d = 0, span = 0;
  bool fits = !runs_.empty() && !__builtin_sub_overflow(step, last_, &d) &&
              !__builtin_sub_overflow(step, runs_.back().first, &span);
  if (fits && runs_.back().count == 1) runs_.back().delta = d;
  fits = fits && d == runs_.back().delta;
  if (fits) ++runs_.back().count;
  else runs_.push_back({step, 0, 1});
  last_ = step;
  ++size_;
}

std::int64_t StepTrail::step(const At& at) const {
  const Run& r = runs_[at.run];
  return r.first + at.in_run * r.delta;
}

void StepTrail::advance(At& at) const {
  if (++at.in_run == runs_[at.run].count) ++at.run, at.in_run = 0;
}

namespace {
// The run's phase, from its RUN_CONFIG (intrinsic if it does not say: the tool refuses such a run itself).
Phase phaseOf(const LogEvent& e, const BoundsContext& ctx) {
  run_config_t m{};
  std::string why;
  if (e.channel != ch::runConfig.name || !decodeChecked(e.data.data(), e.data.size(), ctx, m, why))
    return Phase::Intrinsic;
  try {
    return parseRunConfigText(m.config_yaml).phase;
  } catch (const std::exception&) {
    return Phase::Intrinsic;
  }
}
}  // namespace

StepOrdered::StepOrdered(std::function<Pass(bool quiet)> open, const ProtocolConfig& protocol)
    : open_(std::move(open)), name_bytes_(protocol.limits.name_bytes) {
  const BoundsContext ctx{&protocol, nullptr};
  LogEvent e;
  {  // Where the run's RUN_CONFIG is (a logger's log begins with it), its run id and its phase.
    Pass find = open_(true);
    for (std::int64_t at = 0; find.next(e); ++at)
      if (find.take(e)) {
        config_at_ = at;
        peekRunId(e.data.data(), e.data.size(), name_bytes_, run_id_);
        phase_ = phaseOf(e, ctx);
        break;
      }
  }
  Pass first = open_(true);
  for (std::int64_t at = 0; first.next(e); ++at) {
    if (!ofRun(first, e, at)) continue;
    Channel& c = channelOf(e.channel);
    const std::optional<StepKey> key = stepKeyOf(e, phase_, ctx);
    // A message whose content cannot say goes with the one before it on its channel (the edge refuses it anyway).
    c.trail.add(key ? key->step : c.trail.size() > 0 ? c.trail.last() : StepKey::kBefore);
    if (key && isSerialChannel(e.channel) && key->step >= 0) {
      first_step_ = first_step_ < 0 ? key->step : std::min(first_step_, key->step);
      last_step_ = std::max(last_step_, key->step);
    }
  }
  if (first.read_through) first.read_through();
  pass_ = open_(false);
}

bool StepOrdered::ofRun(Pass& pass, const LogEvent& e, std::int64_t at) const {
  if (pass.take(e)) return true;
  // Before the RUN_CONFIG: the events of the run's id (a log interleaved anew may put some there).
  std::string id;
  return at < config_at_ && !run_id_.empty() && peekRunId(e.data.data(), e.data.size(), name_bytes_, id) &&
         id == run_id_;
}

StepOrdered::Channel& StepOrdered::channelOf(const std::string& name) {
  const auto [it, added] = index_.emplace(name, channels_.size());
  if (added) {
    channels_.emplace_back();
    channels_.back().name = name;
    channels_.back().rank = stepRank(name);
  }
  return channels_[it->second];
}

void StepOrdered::rewind() {
  pass_ = open_(false);
  read_ = 0;
  for (Channel& c : channels_) c.at = {}, c.given = 0, c.held.clear();
  held_ = most_held_ = 0;
  left_out_ = 0;
  ended_ = false;
}

bool StepOrdered::readFor(Channel& c) {
  LogEvent e;
  while (c.held.empty()) {
    if (!pass_.next(e)) return false;
    if (!ofRun(pass_, e, read_++)) {
      ++left_out_;
      continue;
    }
    const auto it = index_.find(e.channel);
    if (it == index_.end()) continue;  // written after the first reading (a log still growing): not given
    Channel& to = channels_[it->second];
    if (to.given + static_cast<std::int64_t>(to.held.size()) >= to.trail.size()) continue;  // (the same)
    to.held.push_back(std::move(e));
    ++held_;
  }
  return true;
}

bool StepOrdered::next(LogEvent& e, StepKey& key) {
  if (ended_) return false;
  Channel* best = nullptr;
  for (Channel& c : channels_) {
    if (c.given == c.trail.size()) continue;
    const StepKey k{c.trail.step(c.at), c.rank};
    if (!best || k < key || (!(key < k) && c.name < best->name)) best = &c, key = k;
  }
  if (!best) {  // every message given: the rest of the reading (what it skips is said and counted)
    while (pass_.next(e))
      if (!ofRun(pass_, e, read_++)) ++left_out_;
    ended_ = true;
    return false;
  }
  if (!readFor(*best))
    throw std::runtime_error("the log changed while it was read: " + std::to_string(best->trail.size()) + " " +
                             best->name + " messages of the run, then fewer");
  e = std::move(best->held.front());
  best->held.pop_front();
  --held_;
  most_held_ = std::max(most_held_, held_);
  best->trail.advance(best->at);
  ++best->given;
  return true;
}

}  // namespace afford
