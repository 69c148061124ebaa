// afford-hostile: a hostile publisher for tests (tests/hostile). It listens to
// a live run on a bus, keeps copies of the run's own traffic, and once the run
// is under way publishes --messages bad messages over the run's channels:
//
//   random      random bytes (sometimes up to 60 KB), with or without a right fingerprint
//   large       random bytes of 64 to 256 KB (LCM sends them in fragments), with a right fingerprint
//   truncated   a real message cut short
//   flipped     a real message with 1 to 8 bits flipped
//   size        a real message with a size field (array size or string length) set
//               to 0, -1, max+1, the bytes left + 1 or huge; half of them re-sealed
//   run_id      a real message of another run id (re-sealed)
//   step        a real message with another step (re-sealed)
//   serial      a real message with another serial: next, random, huge, negative (re-sealed)
//   nan         a real message with NaN or an infinity in a field (re-sealed)
//   duplicate   an earlier real message, as it was
//   resend      a storm of RESEND requests for real channels, some for huge ranges
//   status      a real STATUS whose counts lie (x1000, +1, huge), re-sealed; or a
//               STATUS of a process that does not exist
//   config      a RUN_CONFIG of another run, or with text that is not YAML
//   paths       names and paths that climb out of a folder: the run's own
//               RUN_CONFIG with a run id such as ../../DIR/x or /DIR/x, or with
//               a fresh run id and run.checkpoint (or extrinsic.checkpoint) in
//               DIR (--outside DIR); and the logger's STATUS (DONE) naming DIR
//               as the run's log folder
//   control     distinct RUN_CONTROL messages of the run (START at any step):
//               a flood the logger must not record without bound
//   statusflood STATUS of made-up processes and pids: a flood that receivers
//               must not remember without bound
//   forge       perfect forgeries: the next serial of a run channel with the
//               digest chain right (a field changed), a STOP of the run, a
//               FAILED STATUS of one of its processes; on an unauthenticated
//               bus these would be taken (docs/security.md); on a keyed bus
//               (--tagged) they carry a tag of another key and must all be dropped
//
// "Re-sealed": the tool recomputes the trailing digest, as a forger who knows
// the protocol would, so the message reaches the checks behind the digest.
// Only `forge` forges a message the real publisher is about to send (the next
// serial with the right chain digest), or STOPs the run: no receiver on an
// unauthenticated bus can tell those from the real ones (docs/security.md).
// --tagged: the bus is keyed; the tool takes the trailing 32-byte tag off what
// it hears, and adds a tag of a key of its own (--forge-key, else a random
// one) to what it sends.
#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>
#include <yaml-cpp/yaml.h>

#include <algorithm>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "afford/auth.hpp"
#include "afford/protocol.hpp"
#include "afford/config.hpp"
#include "afford/node.hpp"
#include "afford/process_main.hpp"
#include "afford/seal.hpp"
#include "afford/bounds.hpp"
#include "afford/edge.hpp"
#include "afford/wire.hpp"
#include "logger/logger.hpp"

namespace {

using Bytes = std::vector<std::uint8_t>;

// The size fields of a real message of the channel's type (offsets, widths):
// the bounds walk records them on the way.
afford::ProtocolConfig g_protocol;
template <class Msg>
std::vector<afford::wire::SizeField> sizesOf(const Bytes& b) {
  std::vector<afford::wire::SizeField> sizes;
  std::string why;
  afford::wire::checkWire<Msg>(b.data(), b.size(), afford::boundsFor<Msg>({&g_protocol, nullptr}), why, &sizes);
  return sizes;
}

struct Channel {
  std::int64_t hash = 0;
  std::function<std::vector<afford::wire::SizeField>(const Bytes&)> sizes;
  // Decode, change a field, encode again (nan, step, serial, run_id); false if not this type.
  std::function<bool(Bytes&, const std::function<void(void*)>&)> edit;
};

template <class Msg>
Channel channelOf() {
  Channel c;
  c.hash = Msg::getHash();
  c.sizes = [](const Bytes& b) { return sizesOf<Msg>(b); };
  c.edit = [](Bytes& b, const std::function<void(void*)>& change) {
    Msg m;
    std::string why;
    if (!afford::decodeChecked(b.data(), b.size(), {&g_protocol, nullptr}, m, why)) return false;
    change(&m);
    b.assign(static_cast<std::size_t>(m.getEncodedSize()), 0);
    m.encode(b.data(), 0, static_cast<int>(b.size()));
    return true;
  };
  return c;
}

class Hostile {
 public:
  Hostile(lcm::LCM& lcm, std::uint64_t seed, std::string outside, std::shared_ptr<const afford::BusKey> forge_key,
          bool tagged)
      : lcm_(lcm), rng_(seed), outside_(std::move(outside)), forge_key_(std::move(forge_key)), tagged_(tagged) {
    using namespace afford;
    channels_[ch::scene.name] = channelOf<scene_t>();
    channels_[ch::focus.name] = channelOf<focus_t>();
    channels_[ch::prediction.name] = channelOf<prediction_t>();
    channels_[ch::decision.name] = channelOf<decision_t>();
    channels_[ch::effect.name] = channelOf<effect_t>();
    channels_[ch::probe.name] = channelOf<object_probe_t>();
    channels_[ch::affordanceTable.name] = channelOf<affordance_table_t>();
    channels_[ch::result.name] = channelOf<run_result_t>();
    channels_[ch::look.name] = channelOf<look_t>();
    channels_[ch::forwardQuery.name] = channelOf<forward_query_t>();
    channels_[ch::forwardPrediction.name] = channelOf<forward_prediction_t>();
    channels_[ch::extrinsicResult.name] = channelOf<extrinsic_result_t>();
    channels_[ch::goal.name] = channelOf<goal_t>();
    channels_[ch::goalResult.name] = channelOf<goal_result_t>();
    channels_[ch::status.name] = channelOf<process_status_t>();
    channels_[ch::resend.name] = channelOf<resend_t>();
    channels_[ch::runConfig.name] = channelOf<run_config_t>();
    channels_[ch::runControl.name] = channelOf<run_control_t>();
    for (const auto& [name, c] : channels_) lcm_.subscribe(name, &Hostile::onMessage, this)->setQueueCapacity(100000);
  }

  // Copies of the run's traffic kept so far.
  std::size_t heard() const {
    std::size_t n = 0;
    for (const auto& [ch, list] : heard_) n += list.size();
    return n;
  }
  bool runUnderWay() const { return heard_.count(afford::ch::focus.name) > 0; }

  void send(const char* kind) {
    std::string ch;
    Bytes b;
    const std::string k = kind;
    if (k == "large") {
      ch = randomChannel();
      b.resize(pick(65536, 256 * 1024));
      for (auto& x : b) x = static_cast<std::uint8_t>(rng_());
      writeBig(b, 0, 8, static_cast<std::uint64_t>(channels_[ch].hash));
    } else if (k == "random") {
      ch = randomChannel();
      const std::size_t n = coin(0.05) ? pick(1000, 60000) : pick(0, 2000);
      b.resize(n);
      for (auto& x : b) x = static_cast<std::uint8_t>(rng_());
      if (n >= 8 && coin(0.5)) writeBig(b, 0, 8, static_cast<std::uint64_t>(channels_[ch].hash));
    } else if (k == "resend") {
      for (std::size_t i = 0, n = pick(1, 10); i < n; ++i) {
        afford::resend_t r{};
        r.run_id = run_;
        r.step = 0;
        r.channel = realChannel();
        r.first = coin(0.2) ? static_cast<std::int64_t>(pick(0, 1'000'000'000'000)) : static_cast<std::int64_t>(pick(0, 3000));
        r.last = r.first + static_cast<std::int64_t>(coin(0.3) ? pick(0, 1'000'000'000) : pick(0, 200));
        r.requester = "hostile";
        r.config_digest = config_.digest;  // the run's request, as heard
        const Bytes s = afford::sealed(r);
        publish(afford::ch::resend.name, s);
      }
      return;
    } else if (k == "paths") {
      return sendPaths();
    } else if (k == "control") {
      afford::run_control_t c{};
      c.run_id = run_;
      c.step = static_cast<std::int64_t>(pick(0, 1'000'000'000));
      c.command = afford::run_control_t::START;
      c.config_digest = coin(0.5) ? config_.digest : static_cast<std::int64_t>(rng_());
      b = afford::sealed(c);
      ch = afford::ch::runControl.name;
    } else if (k == "statusflood") {
      afford::process_status_t st{};
      st.run_id = "";
      st.step = -1;
      const char* names[] = {"environment", "eye", "predictors", "motivation", "planner", "logger"};
      st.process = coin(0.5) ? std::string(names[pick(0, 5)]) : "ghost" + std::to_string(pick(0, 1'000'000));
      st.pid = static_cast<std::int32_t>(pick(100000, 2'000'000'000));
      st.beat = static_cast<std::int64_t>(pick(0, 1000));
      st.state = afford::process_status_t::WAITING;
      st.config_digest = st.counts_config = 0;
      st.n_channels = 0;
      st.n_takes = 0;
      st.started = 0;
      st.n_copies = 0;
      b = afford::sealed(st);
      ch = afford::ch::status.name;
    } else if (k == "forge") {
      return sendForgery();
    } else if (k == "config") {
      afford::run_config_t c{};
      c.run_id = coin(0.5) ? run_ + "-not" : run_;
      c.step = 0;
      c.request = static_cast<std::int64_t>(rng_());
      c.seed = 1;
      c.experiment = "base";
      c.system = "IMP";
      c.config_yaml = coin(0.5) ? "{{{ not: yaml" : "run: {steps: 5}";
      b = afford::sealed(c);
      ch = afford::ch::runConfig.name;
    } else {
      if (!copy(k == "status" ? afford::ch::status.name : realChannel(), ch, b)) return;
      Channel& c = channels_[ch];
      if (k == "truncated") {
        b.resize(pick(0, b.size() - 1));
      } else if (k == "flipped") {
        for (std::size_t i = 0, n = pick(1, 8); i < n; ++i) b[pick(0, b.size() - 1)] ^= static_cast<std::uint8_t>(1u << pick(0, 7));
      } else if (k == "size") {
        const auto sizes = c.sizes(b);
        if (sizes.empty()) return;
        const auto& f = sizes[pick(0, sizes.size() - 1)];
        const std::int64_t left = static_cast<std::int64_t>(b.size() - f.offset);
        const std::int64_t values[] = {0, -1, f.max + 1, left + 1, 0x10000001, 0x01000000, std::numeric_limits<std::int32_t>::max()};
        writeBig(b, f.offset, f.width, static_cast<std::uint64_t>(values[pick(0, 6)]));
        if (coin(0.5)) afford::sealBuffer(b.data(), b.size());
      } else if (k == "duplicate") {
        // as it was
      } else if (!editField(k, ch, b)) {
        return;
      }
    }
    publish(ch, b);
  }

  // The run's own RUN_CONFIG with a path-climbing run id, or with checkpoints
  // outside; the logger's DONE naming a folder outside.
  void sendPaths() {
    if (run_.empty() || config_.run_id.empty() || outside_.empty()) return;
    const std::string n = std::to_string(pick(0, 999999));
    const int which = static_cast<int>(pick(0, 5));
    if (which == 5) {
      afford::process_status_t st{};
      st.run_id = run_;
      st.step = 0;
      st.process = "logger";
      st.pid = static_cast<std::int32_t>(pick(100000, 2'000'000'000));
      st.beat = std::numeric_limits<std::int32_t>::max();
      st.state = afford::process_status_t::DONE;
      st.config_digest = config_.digest;
      st.detail = outside_ + "/" + run_;
      st.n_channels = 0;
      st.n_takes = 0;
      st.counts_run = run_;
      st.counts_config = config_.digest;
      st.started = 0;
      st.n_copies = 0;
      publish(afford::ch::status.name, afford::sealed(st));
      return;
    }
    afford::run_config_t c = config_;
    YAML::Node node = YAML::Load(c.config_yaml);
    // From any folder, up to / and down into the folder outside.
    std::string climb;
    for (int i = 0; i < 24; ++i) climb += "../";
    climb += outside_.substr(1);
    switch (which) {
      case 0: c.run_id = climb + "/climb-" + n; break;
      case 1: c.run_id = outside_ + "/abs-" + n; break;  // absolute: begins with '/'
      case 2: c.run_id = ".." ; break;
      case 3:  // a fresh, safe run id; its checkpoint outside
        c.run_id = "forged-" + n;
        node["run"]["checkpoint"] = outside_ + "/forged-" + n + "/predictors.ckpt";
        break;
      default:  // the same, climbing from the predictors' folder
        c.run_id = "forged-" + n;
        node["run"]["checkpoint"] = climb + "/forged-" + n + "/predictors.ckpt";
        break;
    }
    c.config_yaml = afford::emitYaml(node);
    publish(afford::ch::runConfig.name, afford::sealed(c));
  }

  // A perfect forgery of the next message on a run channel, or a STOP, or a FAILED STATUS.
  void sendForgery() {
    if (run_.empty()) return;
    const double kind = std::uniform_real_distribution<double>(0, 1)(rng_);
    if (kind < 0.05) {
      afford::run_control_t c{};
      c.run_id = run_;
      c.step = 0;
      c.command = afford::run_control_t::STOP;
      c.config_digest = config_.digest;  // a perfect forgery: the request as heard
      publish(afford::ch::runControl.name, afford::sealed(c));
      return;
    }
    if (kind < 0.1) {
      afford::process_status_t st{};
      st.run_id = run_;
      st.step = 1;
      const char* names[] = {"environment", "eye", "predictors", "motivation", "planner"};
      st.process = names[pick(0, 4)];
      st.pid = pids_.count(st.process) ? pids_[st.process] : 1;
      st.beat = std::numeric_limits<std::int64_t>::max();
      st.state = afford::process_status_t::FAILED;
      st.config_digest = config_.digest;
      st.counts_config = 0;
      st.detail = "forged failure";
      st.n_channels = 0;
      st.n_takes = 0;
      st.started = 0;
      st.n_copies = 0;
      publish(afford::ch::status.name, afford::sealed(st));
      return;
    }
    std::vector<std::string> candidates;
    for (const auto& [ch, l] : last_) candidates.push_back(ch);
    if (candidates.empty()) return;
    const std::string ch = candidates[pick(0, candidates.size() - 1)];
    Bytes b = last_[ch].bytes;
    const std::int64_t serial = last_[ch].serial + 1, prev = last_[ch].digest;
    const std::int64_t nudge = static_cast<std::int64_t>(pick(1, 3));
    const bool ok = channels_[ch].edit(b, [&](void* p) {
      using namespace afford;
      auto next = [&](auto* m) {
        if constexpr (wire::Bounds<std::remove_pointer_t<decltype(m)>>::kSerial) {
          m->serial = serial;
          m->prev_digest = prev;
        }
      };
      if (ch == ch::scene.name) { auto* m = static_cast<scene_t*>(p); next(m); m->step += 1; }
      if (ch == ch::focus.name) { auto* m = static_cast<focus_t*>(p); next(m); m->step += 1; if (!m->image.empty()) m->image[0] ^= 0xFF; }
      if (ch == ch::prediction.name) { auto* m = static_cast<prediction_t*>(p); next(m); m->step += 1; }
      if (ch == ch::decision.name) { auto* m = static_cast<decision_t*>(p); next(m); m->step += 1; m->acted = !m->acted; }
      if (ch == ch::effect.name) { auto* m = static_cast<effect_t*>(p); next(m); m->step += 1; }
      if (ch == ch::probe.name) { auto* m = static_cast<object_probe_t*>(p); next(m); }
      if (ch == ch::affordanceTable.name) { auto* m = static_cast<affordance_table_t*>(p); next(m); m->step += nudge; }
      if (ch == ch::result.name) { auto* m = static_cast<run_result_t*>(p); next(m); m->weights_checksum = "0123456789abcdef"; m->checkpoint = outside_ + "/forged.ckpt"; }
      if (ch == ch::look.name) { auto* m = static_cast<look_t*>(p); next(m); }
      if (ch == ch::forwardQuery.name) { auto* m = static_cast<forward_query_t*>(p); next(m); }
      if (ch == ch::forwardPrediction.name) { auto* m = static_cast<forward_prediction_t*>(p); next(m); }
      if (ch == ch::extrinsicResult.name) { auto* m = static_cast<extrinsic_result_t*>(p); next(m); m->success = !m->success; }
      if (ch == ch::goal.name) { auto* m = static_cast<goal_t*>(p); next(m); m->id += 1; }
      if (ch == ch::goalResult.name) { auto* m = static_cast<goal_result_t*>(p); next(m); m->reached = !m->reached; }
    });
    if (!ok) return;
    afford::sealBuffer(b.data(), b.size());
    publish(ch, b);
  }

  std::size_t sent() const { return sent_; }
  const std::map<std::string, std::size_t>& sentPerChannel() const { return per_channel_; }

 private:
  void onMessage(const lcm::ReceiveBuffer* rb, const std::string& ch) {
    const auto* d = static_cast<const std::uint8_t*>(rb->data);
    std::size_t size = rb->data_size;
    if (tagged_) {  // the real messages end with a stamp and a tag this tool cannot make
      if (size < afford::BusKey::kTrailerBytes) return;
      size -= afford::BusKey::kTrailerBytes;
    }
    // Only what looks real is copied (its own bad messages come back to it too).
    if (!afford::sealIntact(d, size)) return;
    auto& list = heard_[ch];
    if (list.size() < 2000) list.emplace_back(d, d + size);
    else list[pick(0, list.size() - 1)] = Bytes(d, d + size);
    std::string run;
    if (ch == afford::ch::focus.name && afford::peekRunId(d, size, 4096, run)) run_ = run;
    std::string why;
    if (ch == afford::ch::runConfig.name) {
      afford::run_config_t c{};
      if (afford::decodeChecked(d, size, {&g_protocol, nullptr}, c, why) && c.run_id == run_) config_ = c;
      else if (config_.run_id.empty() && afford::decodeChecked(d, size, {&g_protocol, nullptr}, c, why)) config_ = c;
    }
    if (ch == afford::ch::status.name) {
      afford::process_status_t st{};
      if (afford::decodeChecked(d, size, {&g_protocol, nullptr}, st, why) && st.beat < (1 << 30)) pids_[st.process] = st.pid;
    }
    // The latest message of each run channel (its serial and digest), for `forge`.
    afford::RunHeader h;
    if (afford::isSerialChannel(ch) && afford::peekRunHeader(d, static_cast<std::uint32_t>(size), h) && h.run_id == run_ &&
        (!last_.count(ch) || h.serial > last_[ch].serial)) {
      std::int64_t digest = 0;
      for (std::size_t i = size - 8; i < size; ++i) digest = (digest << 8) | d[i];
      last_[ch] = {h.serial, digest, Bytes(d, d + size)};
    }
  }

  // A field of a real message changed, then re-sealed.
  bool editField(const std::string& kind, const std::string& ch, Bytes& b) {
    Channel& c = channels_[ch];
    const double bad[] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                          -std::numeric_limits<double>::infinity()};
    const double nan = bad[pick(0, 2)];
    const std::int64_t serials[] = {1, static_cast<std::int64_t>(pick(0, 100000)), std::numeric_limits<std::int64_t>::max(), -1};
    const std::int64_t serial_pick = serials[pick(0, 3)];
    const std::int64_t step = static_cast<std::int64_t>(pick(0, 20000)) - 10;
    const std::string other_run = run_ + "-" + std::to_string(pick(0, 99));
    const bool ok = c.edit(b, [&](void* p) {
      using namespace afford;
      auto common = [&](auto* m) {
        if (kind == "run_id") m->run_id = other_run;
        if (kind == "step") m->step = step;
        if constexpr (wire::Bounds<std::remove_pointer_t<decltype(m)>>::kSerial)
          if (kind == "serial") m->serial = serial_pick == 1 ? m->serial + 1 : serial_pick;
      };
      if (ch == ch::scene.name) { auto* m = static_cast<scene_t*>(p); common(m); if (kind == "nan") m->goal_distance = nan; }
      if (ch == ch::focus.name) { auto* m = static_cast<focus_t*>(p); common(m); if (kind == "nan") m->x = nan; }
      if (ch == ch::prediction.name) { auto* m = static_cast<prediction_t*>(p); common(m); if (kind == "nan" && !m->affordance.empty()) m->affordance[pick(0, m->affordance.size() - 1)] = nan; }
      if (ch == ch::decision.name) { auto* m = static_cast<decision_t*>(p); common(m); if (kind == "nan") m->motivation = nan; }
      if (ch == ch::effect.name) { auto* m = static_cast<effect_t*>(p); common(m); if (kind == "nan") m->after_x = nan; }
      if (ch == ch::probe.name) { auto* m = static_cast<object_probe_t*>(p); common(m); }
      if (ch == ch::affordanceTable.name) { auto* m = static_cast<affordance_table_t*>(p); common(m); if (kind == "nan" && !m->affordance.empty() && !m->affordance[0].empty()) m->affordance[0][0] = nan; }
      if (ch == ch::result.name) { auto* m = static_cast<run_result_t*>(p); common(m); }
      if (ch == ch::look.name) { auto* m = static_cast<look_t*>(p); common(m); if (kind == "nan") m->x = nan; }
      if (ch == ch::forwardQuery.name) { auto* m = static_cast<forward_query_t*>(p); common(m); if (kind == "nan") m->x = nan; }
      if (ch == ch::forwardPrediction.name) { auto* m = static_cast<forward_prediction_t*>(p); common(m); if (kind == "nan" && !m->where_x.empty()) m->where_x[0] = nan; }
      if (ch == ch::extrinsicResult.name) { auto* m = static_cast<extrinsic_result_t*>(p); common(m); if (kind == "nan") m->utility = nan; }
      if (ch == ch::goal.name) { auto* m = static_cast<goal_t*>(p); common(m); if (kind == "nan") m->x = nan; }
      if (ch == ch::goalResult.name) { auto* m = static_cast<goal_result_t*>(p); common(m); if (kind == "nan") m->distance = nan; }
      if (ch == ch::status.name) {
        auto* m = static_cast<process_status_t*>(p);
        if (coin(0.2)) m->process = "ghost" + std::to_string(pick(0, 9));
        for (auto& n : m->counts) n = coin(0.3) ? n + 1 : coin(0.5) ? n * 1000 + 7 : std::numeric_limits<std::int64_t>::max() / 2;
      }
    });
    if (ok) afford::sealBuffer(b.data(), b.size());
    return ok;
  }

  bool copy(const std::string& want, std::string& ch, Bytes& b) {
    auto it = heard_.find(want);
    if (it == heard_.end() || it->second.empty()) return false;
    ch = want;
    b = it->second[pick(0, it->second.size() - 1)];
    return !b.empty();
  }
  std::string realChannel() {
    std::vector<std::string> run_channels;
    for (const auto& [ch, list] : heard_)
      if (ch != afford::ch::status.name && ch != afford::ch::resend.name && ch != afford::ch::runConfig.name && !list.empty())
        run_channels.push_back(ch);
    return run_channels.empty() ? std::string(afford::ch::focus.name) : run_channels[pick(0, run_channels.size() - 1)];
  }
  std::string randomChannel() {
    auto it = channels_.begin();
    std::advance(it, static_cast<long>(pick(0, channels_.size() - 1)));
    return it->first;
  }
  void publish(const std::string& ch, const Bytes& b) {
    if (tagged_) {  // a tag of another key (or random bytes): a receiver with the bus's key drops it
      const afford::Stamp stamp{rng_(), forged_++, std::chrono::duration_cast<std::chrono::milliseconds>(
                                                         std::chrono::system_clock::now().time_since_epoch())
                                                         .count()};
      Bytes t = forge_key_ ? forge_key_->tagged(ch, b.data(), b.size(), stamp) : b;
      if (!forge_key_)
        for (std::size_t i = 0; i < afford::BusKey::kTrailerBytes; ++i) t.push_back(static_cast<std::uint8_t>(rng_()));
      lcm_.publish(ch, t.data(), static_cast<unsigned>(t.size()));
    } else {
      lcm_.publish(ch, b.data(), static_cast<unsigned>(b.size()));
    }
    ++sent_;
    ++per_channel_[ch];
  }
  static void writeBig(Bytes& b, std::size_t at, int width, std::uint64_t v) {
    for (int i = 0; i < width && at + static_cast<std::size_t>(i) < b.size(); ++i)
      b[at + static_cast<std::size_t>(width - 1 - i)] = static_cast<std::uint8_t>(v >> (8 * i));
  }
  std::size_t pick(std::size_t lo, std::size_t hi) { return std::uniform_int_distribution<std::size_t>(lo, hi)(rng_); }
  bool coin(double p) { return std::uniform_real_distribution<double>(0, 1)(rng_) < p; }

  lcm::LCM& lcm_;
  std::mt19937_64 rng_;
  std::map<std::string, Channel> channels_;
  std::map<std::string, std::vector<Bytes>> heard_;
  std::string run_;
  std::string outside_;
  std::shared_ptr<const afford::BusKey> forge_key_;
  bool tagged_ = false;
  afford::run_config_t config_{};  // the run's, as heard
  std::map<std::string, std::int32_t> pids_;
  struct Last {
    std::int64_t serial = -1, digest = 0;
    Bytes bytes;
  };
  std::map<std::string, Last> last_;
  std::size_t sent_ = 0;
  std::uint64_t forged_ = 0;  // counters of the stamps forged with another key
  std::map<std::string, std::size_t> per_channel_;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"afford-hostile: floods a live run with bad messages built from its own traffic (tests)", "afford-hostile"};
  std::string url = "udpm://239.255.76.67:7667?ttl=0";
  std::size_t messages = 10000;
  std::uint64_t seed = 1;
  int burst = 40, pause_ms = 5;
  std::vector<std::string> kinds = {"random", "large", "truncated", "flipped", "size", "run_id", "step", "serial", "nan",
                                    "duplicate", "resend", "status", "config"};
  app.add_option("--lcm-url", url, "the run's bus")->capture_default_str();
  app.add_option("--messages", messages, "bad messages to publish (a RESEND storm counts its requests)")->capture_default_str();
  app.add_option("--seed", seed, "of the tool's own random choices")->capture_default_str();
  app.add_option("--burst", burst, "messages per burst")->capture_default_str();
  app.add_option("--pause-ms", pause_ms, "between bursts")->capture_default_str();
  app.add_option("--kinds", kinds, "kinds of bad messages, chosen uniformly")->capture_default_str();
  std::string config_dir = afford::defaultConfigDir();
  app.add_option("--config-dir", config_dir, "folder of defaults.yaml (the protocol's limits)")->capture_default_str();
  std::string outside, forge_key_file;
  bool tagged = false;
  app.add_option("--outside", outside, "paths: the folder forged names and paths point into (absolute)");
  app.add_flag("--tagged", tagged, "the bus is keyed: take tags off what is heard, tag what is sent with another key");
  app.add_option("--forge-key", forge_key_file, "with --tagged: tag with this key (default: random bytes)");
  CLI11_PARSE(app, argc, argv);
  g_protocol = afford::loadProtocol(config_dir);
  if (std::find(kinds.begin(), kinds.end(), "paths") != kinds.end() && (outside.empty() || outside[0] != '/')) {
    std::fprintf(stderr, "afford-hostile: --kinds paths needs --outside, an absolute folder\n");
    return 2;
  }
  std::shared_ptr<const afford::BusKey> forge_key;
  if (!forge_key_file.empty()) forge_key = std::make_shared<const afford::BusKey>(afford::BusKey::fromFile(forge_key_file));
  afford::installStopHandlers();
  // Its own bus opened raw: it hears (and sends) what LCM's default bounds let through.
  lcm::LCM lcm(url);
  if (!lcm.good()) {
    std::fprintf(stderr, "afford-hostile: cannot open %s\n", url.c_str());
    return 1;
  }
  Hostile h(lcm, seed, outside, forge_key, tagged);
  while (!h.runUnderWay() && !afford::stopRequested()) lcm.handleTimeout(50);  // a run's traffic to copy
  std::mt19937_64 pick(seed ^ 0x5eed);
  while (h.sent() < messages && !afford::stopRequested()) {
    for (int i = 0; i < burst && h.sent() < messages; ++i)
      h.send(kinds[std::uniform_int_distribution<std::size_t>(0, kinds.size() - 1)(pick)].c_str());
    while (lcm.handleTimeout(0) > 0) {
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(pause_ms));  // the tool's own pacing, not a test's wait
  }
  std::printf("sent %zu bad messages:", h.sent());
  for (const auto& [ch, n] : h.sentPerChannel()) std::printf(" %s %zu", ch.c_str(), n);
  std::printf("\n");
  return 0;
}
