// One node alone on a memq:// bus. A whole run of the choreography is recorded
// first; each node is then started by itself and fed, from that recording, the
// messages its peers published, in a chosen order: as recorded, shuffled,
// duplicated, or with some missing until the node asks for them (RESEND). The
// harness stands in for the peers: it answers RESEND from the recording and,
// once everything is fed, sends the peers' heartbeats (STATUS with their
// counts). What the node publishes must equal, byte for byte and channel by
// channel, what it published in the recorded run.
#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>
#include <spdlog/sinks/ostream_sink.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "afford/protocol.hpp"
#include "afford/processes.hpp"
#include "afford/edge.hpp"
#include "afford/process_status_t.hpp"
#include "afford/resend_t.hpp"
#include "afford/run_control_t.hpp"
#include "afford/seal.hpp"
#include "logger/logger.hpp"
#include "tests/in_process.hpp"
#include "tests/reference_loops.hpp"
#include "tests/support.hpp"
#include "experiment/design/experiment_file.hpp"

namespace afford {
namespace {

using test::Bytes;
using test::Event;

enum class Feed { InOrder, OutOfOrder, Duplicated, MissingThenResent, ChannelByChannel };

const char* name(Feed f) {
  switch (f) {
    case Feed::InOrder:
      return "InOrder";
    case Feed::OutOfOrder:
      return "OutOfOrder";
    case Feed::Duplicated:
      return "Duplicated";
    case Feed::MissingThenResent:
      return "MissingThenResent";
    case Feed::ChannelByChannel:
      return "ChannelByChannel";
  }
  return "?";
}

std::int64_t serialOf(const Event& e) {
  RunHeader h;
  return peekRunHeader(e.data.data(), static_cast<std::uint32_t>(e.data.size()), h) ? h.serial : -1;
}

struct Recording {
  std::vector<Event> events;  // every message of the run but STATUS, in the order it went out
  Phase phase = Phase::Intrinsic;
  std::string run_id;
};

struct AloneOutcome {
  std::map<std::string, std::vector<Bytes>> outputs;  // what the node published, per channel
  std::string error;                                 // a wait that did not end
  int fed = 0;                                       // messages published to the node by the harness
  int withheld = 0;                                  // messages left out of the feed
  int resent = 0;                                    // messages re-sent on the node's RESEND
  std::string log;
};

// The messages of `rec` that `process` took in (its peers' data messages) and
// those it published itself.
struct Split {
  Bytes config, start, stop;
  std::vector<Event> inputs;
  std::map<std::string, std::vector<Bytes>> outputs;
  std::map<std::string, std::size_t> before_stop;  // outputs published before STOP, per channel
  std::map<std::string, std::map<std::int64_t, Bytes>> by_serial;  // inputs, per channel and serial
};

// `takes`: the channels the node subscribes to (the bus gives it nothing else).
Split split(const Recording& rec, const std::string& process, const std::vector<std::string>& takes) {
  Split s;
  for (const Event& e : rec.events) {
    if (e.channel == ch::runConfig.name) {
      if (s.config.empty()) s.config = e.data;
      continue;
    }
    if (e.channel == ch::runControl.name) {
      run_control_t c;
      c.decode(e.data.data(), 0, static_cast<int>(e.data.size()));
      if (c.command == run_control_t::START && s.start.empty()) s.start = e.data;
      if (c.command == run_control_t::STOP && s.stop.empty()) s.stop = e.data;
      continue;
    }
    if (!isSerialChannel(e.channel)) continue;
    if (publisherOf(e.channel, rec.phase) == process) {
      s.outputs[e.channel].push_back(e.data);
      if (s.stop.empty()) s.before_stop[e.channel] = s.outputs[e.channel].size();
    } else if (std::find(takes.begin(), takes.end(), e.channel) != takes.end()) {
      s.inputs.push_back(e);
      s.by_serial[e.channel][serialOf(e)] = e.data;
    }
  }
  return s;
}

// The order in which the inputs go to the node (indices into Split::inputs).
std::vector<std::size_t> order(const Split& s, Feed feed, std::uint64_t seed, int& withheld) {
  const std::size_t n = s.inputs.size();
  std::mt19937_64 rng(seed);
  std::vector<std::size_t> out(n);
  for (std::size_t i = 0; i < n; ++i) out[i] = i;
  switch (feed) {
    case Feed::InOrder:
      break;
    case Feed::OutOfOrder:  // shuffled within windows of 12: across channels and within each
      for (std::size_t at = 0; at < n; at += 12) std::shuffle(out.begin() + at, out.begin() + std::min(n, at + 12), rng);
      break;
    case Feed::Duplicated: {  // every message once more, up to 30 places later; the first 20 a third time at the end
      std::vector<std::size_t> d;
      std::multimap<std::size_t, std::size_t> copies;  // position -> message
      for (std::size_t i = 0; i < n; ++i) copies.emplace(i + rng() % 31, i);
      for (std::size_t i = 0; i < n + 31; ++i) {
        if (i < n) d.push_back(i);
        auto [b, e] = copies.equal_range(i);
        for (auto it = b; it != e; ++it) d.push_back(it->second);
      }
      for (std::size_t i = 0; i < std::min<std::size_t>(20, n); ++i) d.push_back(i);
      out = d;
      break;
    }
    case Feed::MissingThenResent: {  // the first, the last and about one in eight never fed: the node must ask
      std::vector<std::size_t> kept;
      for (std::size_t i = 1; i + 1 < n; ++i)
        if (rng() % 8 != 0) kept.push_back(i);
      withheld = static_cast<int>(n - kept.size());
      out = kept;
      break;
    }
    case Feed::ChannelByChannel:  // all of one channel, then the next (by name): a catch-up of one far ahead
      std::stable_sort(out.begin(), out.end(),
                       [&](std::size_t a, std::size_t b) { return s.inputs[a].channel < s.inputs[b].channel; });
      break;
  }
  return out;
}

// The channels a node of `process` takes in serial order.
std::vector<std::string> takes(const std::string& process) {
  lcm::LCM lcm("memq://");
  return test::makeNode(process, lcm, std::make_shared<spdlog::logger>(process, std::make_shared<spdlog::sinks::null_sink_mt>()), test::shippedProtocol())->takes();
}

AloneOutcome feedAlone(const Recording& rec, const std::string& process, Feed feed, std::uint64_t seed) {
  AloneOutcome o;
  lcm::LCM lcm("memq://");
  std::ostringstream log;
  auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(log);
  auto logger = std::make_shared<spdlog::logger>(process, sink);
  logger->set_pattern("[%n] %v");
  std::unique_ptr<NodeBase> node = test::makeNode(process, lcm, logger, test::shippedProtocol());
  const Split s = split(rec, process, node->takes());

  // The tap: the node's data messages, and its requests, answered as their publisher would.
  std::vector<std::pair<std::string, Bytes>> answers;
  struct Tap {
    AloneOutcome* o;
    const Split* s;
    const std::string* run;
    std::vector<std::pair<std::string, Bytes>>* answers;
    void on(const lcm::ReceiveBuffer* b, const std::string& ch) {
      const auto* d = static_cast<const std::uint8_t*>(b->data);
      if (s->outputs.count(ch)) o->outputs[ch].emplace_back(d, d + b->data_size);
      if (ch != ch::resend.name) return;
      resend_t r;
      if (r.decode(b->data, 0, static_cast<int>(b->data_size)) < 0 || r.run_id != *run) return;
      auto it = s->by_serial.find(r.channel);
      if (it == s->by_serial.end()) return;
      for (auto m = it->second.lower_bound(r.first); m != it->second.end() && m->first <= r.last; ++m)
        answers->emplace_back(r.channel, m->second);
    }
  } tap{&o, &s, &rec.run_id, &answers};
  lcm.subscribe(".*", &Tap::on, &tap)->setQueueCapacity(1000000);

  auto publish = [&](const std::string& ch, const Bytes& b) { lcm.publish(ch, b.data(), static_cast<unsigned>(b.size())); };
  auto pump = [&] {
    for (bool busy = true; busy;) {
      busy = false;
      while (lcm.handleTimeout(0) > 0) busy = true;
      std::vector<std::pair<std::string, Bytes>> now;
      now.swap(answers);
      for (const auto& [ch, b] : now) publish(ch, b), ++o.resent, busy = true;
      node->tick();
    }
  };
  // The peers' heartbeats: each publisher's STATUS with the counts of all it published.
  std::map<std::string, std::map<std::string, std::int64_t>> counts;
  for (const Event& e : s.inputs) ++counts[publisherOf(e.channel, rec.phase)][e.channel];
  std::int64_t beat = 0;
  run_config_t recorded_config;  // the request the peers' counts are of
  recorded_config.decode(s.config.data(), 0, static_cast<int>(s.config.size()));
  auto heartbeats = [&] {
    int pid = 1000;
    for (const auto& [peer, channels] : counts) {
      process_status_t st{};
      st.run_id = st.counts_run = rec.run_id;
      st.step = 0;
      st.process = peer;
      st.pid = ++pid;
      st.beat = beat;
      st.state = process_status_t::RUNNING;
      st.config_digest = st.counts_config = recorded_config.digest;
      for (const auto& [ch, n] : channels) st.channels.push_back(ch), st.counts.push_back(n), st.held_from.push_back(0);
      st.n_channels = static_cast<int32_t>(st.channels.size());
      st.n_takes = 0;
      st.started = 0;
      st.n_copies = 0;
      publish(ch::status.name, sealed(st));
    }
    ++beat;
  };
  // Wait for a condition, with the heartbeats of the peers as the recovery of a lost tail.
  auto waitFor = [&](const std::function<bool()>& done, const std::string& what) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    auto next_beat = std::chrono::steady_clock::now();
    while (!done()) {
      if (std::chrono::steady_clock::now() > deadline) {
        o.error = "the node did not " + what + " within 30 s";
        return false;
      }
      if (std::chrono::steady_clock::now() >= next_beat) {
        heartbeats();
        next_beat = std::chrono::steady_clock::now() + std::chrono::milliseconds(20);
      }
      lcm.handleTimeout(2);
      pump();
    }
    return true;
  };

  publish(ch::runConfig.name, s.config);
  pump();
  if (!waitFor([&] { return node->state() == process_status_t::READY; }, "take the run's configuration")) {
    o.log = log.str();
    return o;
  }
  publish(ch::runControl.name, s.start);
  pump();
  for (std::size_t i : order(s, feed, seed, o.withheld)) {
    publish(s.inputs[i].channel, s.inputs[i].data);
    ++o.fed;
    pump();
  }
  const bool ran = waitFor(
      [&] {
        for (const auto& [ch, n] : s.before_stop)
          if (o.outputs[ch].size() < n) return false;
        return true;
      },
      "publish what it published before STOP");
  if (ran) {
    publish(ch::runControl.name, s.stop);
    waitFor([&] { return node->runId().empty(); }, "leave the run after STOP");
  }
  node.reset();
  o.log = log.str();
  return o;
}

// The recorded runs, made once.
Recording recordIntrinsic(const std::vector<std::string>& settings, System system = System::IMP) {
  // late1 with its newcomers brought forward into a short run: scenes of every cause.
  YAML::Node c = YAML::Load(test::shippedConfigYaml("late1", system, 7, 260, settings));
  for (YAML::Node o : c["world"]["objects"])
    if (o["appears_at"].as<int>() > 0) o["appears_at"] = 200;
  const std::string yaml = YAML::Dump(c);
  test::InProcessRun run(yaml, system, 7, 260);
  EXPECT_TRUE(run.outcome.ok) << run.outcome.error;
  return Recording{run.events, system == System::GOALS ? Phase::Goals : Phase::Intrinsic, "test-run"};
}
const Recording& intrinsicRecording() {
  static const Recording rec = recordIntrinsic({});
  return rec;
}
// The goals phase (issue 41): GOALS on the same world, the planner deciding for the motivation's goals.
const Recording& goalsRecording() {
  static const Recording rec = recordIntrinsic({}, System::GOALS);
  return rec;
}
// With the memory options of issue 11: the predictors' looks, tried_ago and replay, the motivation's revisits.
const Recording& memoryRecording() {
  static const Recording rec = recordIntrinsic(test::kMemoryOptions);
  return rec;
}

const Recording& extrinsicRecording() {
  static const Recording rec = [] {
    const std::string dir = test::tempDir("alone-extrinsic");
    const std::string config_dir = std::string(AFFORD_SOURCE_DIR) + "/config";
    test::runIntrinsic(parseRunConfigText(test::baseYaml(System::IMP, 6000, 5))).save(dir + "/predictors.ckpt");
    const std::string yaml = emitYaml(extrinsicConfig(config_dir, RunRequest{"base", System::IMP, 11, std::nullopt, {}},
                                                      dir + "/predictors.ckpt", "scenario3"));
    test::InProcessRun run(yaml, System::IMP, 11, 125);
    EXPECT_TRUE(run.outcome.ok) << run.outcome.error;
    // A test of more than one action, each with its scene and its looks.
    EXPECT_GE(run.count(ch::decision.name), 2);
    EXPECT_GE(run.count(ch::look.name), 3 * run.count(ch::decision.name));
    return Recording{run.events, Phase::Extrinsic, "test-run"};
  }();
  return rec;
}

struct Case {
  std::string process;
  Phase phase;
  Feed feed;
  bool memory = false;  // the intrinsic run with the memory options
};

// What the node published alone is what it published in the whole run, channel by channel, byte for byte.
void expectSameOutputs(const Split& s, const AloneOutcome& o, std::uint64_t seed) {
  for (const auto& [ch, want] : s.outputs) {
    const auto it = o.outputs.find(ch);
    const std::vector<Bytes> got = it == o.outputs.end() ? std::vector<Bytes>{} : it->second;
    ASSERT_EQ(got.size(), want.size()) << ch << " (seed " << seed << ")";
    for (std::size_t i = 0; i < want.size(); ++i)
      ASSERT_EQ(got[i], want[i]) << ch << " message " << i << " differs (seed " << seed << ")";
  }
  for (const auto& [ch, got] : o.outputs)
    EXPECT_TRUE(s.outputs.count(ch)) << "published on " << ch << ", which it did not in the whole run";
}

class NodeAlone : public ::testing::TestWithParam<Case> {};

TEST_P(NodeAlone, PublishesTheBytesItPublishedInTheWholeRun) {
  const Case& c = GetParam();
  const Recording& rec = c.phase == Phase::Extrinsic ? extrinsicRecording()
                         : c.phase == Phase::Goals   ? goalsRecording()
                         : c.memory                  ? memoryRecording()
                                                     : intrinsicRecording();
  const Split s = split(rec, c.process, takes(c.process));
  ASSERT_FALSE(s.inputs.empty() && c.process != "environment");
  ASSERT_FALSE(s.outputs.empty());
  for (std::uint64_t seed : {1u, 2u}) {
    const AloneOutcome o = feedAlone(rec, c.process, c.feed, seed);
    ASSERT_TRUE(o.error.empty()) << o.error << "\n" << o.log.substr(0, 4000);
    if (c.feed == Feed::MissingThenResent && !s.inputs.empty()) {
      EXPECT_GT(o.withheld, 0);
      EXPECT_GE(o.resent, o.withheld);  // every withheld message came back on request
    }
    if (c.feed == Feed::Duplicated) {
      EXPECT_GT(o.fed, static_cast<int>(s.inputs.size()));
    }
    expectSameOutputs(s, o, seed);
    if (s.inputs.empty()) break;  // nothing to reorder: one feed says it all
  }
}

// A goals motivation catching up from a snapshot gets one channel far ahead of the others (the FOCUS of
// thousands of steps before their GOAL_RESULTs). With little room to hold inputs (goals.held 32, each kind
// apart), fed all of one channel and then the next, it still ends every goal, in order, and publishes what
// it published in the run. (With one cap for all kinds, the looks took the room the forward predictions
// needed before the next goal could end, and a long catch-up stalled.)
TEST(NodeAloneGoals, TheMotivationFedOneChannelAfterAnotherWithLittleRoomPublishesTheSameBytes) {
  static const Recording rec = recordIntrinsic({"goals.held=32"}, System::GOALS);
  const Split s = split(rec, "motivation", takes("motivation"));
  ASSERT_GT(s.inputs.size(), 200U);
  const AloneOutcome o = feedAlone(rec, "motivation", Feed::ChannelByChannel, 1);
  ASSERT_TRUE(o.error.empty()) << o.error << "\n" << o.log.substr(0, 4000);
  expectSameOutputs(s, o, 1);
}

std::vector<Case> cases() {
  std::vector<Case> out;
  for (Feed f : {Feed::InOrder, Feed::OutOfOrder, Feed::Duplicated, Feed::MissingThenResent}) {
    for (Phase phase : {Phase::Intrinsic, Phase::Extrinsic, Phase::Goals})
      for (const std::string& p : runProcesses(phase, /*recorded=*/false)) out.push_back({p, phase, f});
    for (const char* p : {"predictors", "motivation"}) out.push_back({p, Phase::Intrinsic, f, true});
  }
  return out;
}

INSTANTIATE_TEST_SUITE_P(Each, NodeAlone, ::testing::ValuesIn(cases()), [](const auto& info) {
  const Case& c = info.param;
  return c.process +
         (c.phase == Phase::Extrinsic ? "Extrinsic"
          : c.phase == Phase::Goals   ? "Goals"
          : c.memory                  ? "IntrinsicWithMemory"
                                      : "Intrinsic") +
         name(c.feed);
});

}  // namespace
}  // namespace afford
