// The message edge's handling of a handler that refuses: a refused message is
// expected again (it may have been a forged one); the same message refused
// again, once asked for, fails the run naming the channel instead of asking
// for it without end. And the bus below it: a keyed bus takes only tagged
// messages, a run id that is no safe name is dropped, a RESEND at the largest
// serials and a message larger than the bus takes are handled, forged process
// ids are bounded. What it says of what it drops: a flood costs a few lines.
#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>

#include <chrono>
#include <string>

#include "afford/bus.hpp"
#include "afford/decision_t.hpp"
#include "afford/protocol.hpp"
#include "afford/edge.hpp"
#include "afford/image.hpp"
#include "afford/process_status_t.hpp"
#include "afford/resend_t.hpp"
#include "afford/scene_t.hpp"
#include "tests/said.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {

std::shared_ptr<spdlog::logger> quiet(const std::string& name) {
  return std::make_shared<spdlog::logger>(name, std::make_shared<spdlog::sinks::null_sink_mt>());
}

scene_t sceneOf(const std::string& run, std::int64_t step) {
  scene_t s;
  s.run_id = run;
  s.step = step;
  s.cause = step == 0 ? scene_t::CAUSE_START : scene_t::CAUSE_ACTION;
  s.scan = true;
  s.changes_next = false;
  s.action = step == 0 ? -1 : 0;
  s.action_target_x = s.action_target_y = -1.0;
  s.goal_distance = s.goal_utility = -1.0;
  s.width = s.height = 150;
  s.encoding = scene_t::ENCODING_ZLIB_RGB8;
  s.data = encodeScene(blankScene(150));
  s.size = static_cast<int32_t>(s.data.size());
  s.n_objects = 0;
  return s;
}

struct Refusing : ::testing::Test {
  lcm::LCM lcm{"memq://"};
  RunConfig config = test::shippedConfig();
  ProtocolConfig protocol = test::shippedProtocol();
  Edge environment{lcm, quiet("environment"), "environment", protocol};
  Edge eye{lcm, quiet("eye"), "eye", protocol};
  std::string failure;
  std::vector<std::int64_t> taken;
  int offered_step1 = 0;

  void SetUp() override {
    environment.join("run-1", &config, {});
    eye.join("run-1", &config, {});
    eye.onFailure([this](const std::string& ch, const std::string& why) { failure = ch + ": " + why; });
  }
  void pump() {
    for (int i = 0; i < 200 && !eye.failed() && taken.size() < 3; ++i) {
      while (lcm.handleTimeout(0) > 0) {
      }
      eye.askMissing();
      environment.answerResends();
      lcm.handleTimeout(2);
    }
  }
  // The scenes of steps 0, 1 and 2 published to an eye that refuses step 1's
  // the first `refusals` times it is offered.
  void run(int refusals) {
    eye.subscribe(ch::scene,
        [this, refusals](const scene_t& s) {
          if (s.step == 1 && offered_step1++ < refusals) return Turn::refuse("step 1 is refused");
          taken.push_back(s.step);
          return Turn::take();
        },
        Scope::Run, Order::Serial);
    for (std::int64_t step : {0, 1, 2}) {
      scene_t s = sceneOf("run-1", step);
      environment.publish(ch::scene, s);
    }
    pump();
  }
};

TEST_F(Refusing, TheSameMessageRefusedAgainFailsTheRunNamingTheChannel) {
  run(1000);
  ASSERT_TRUE(eye.failed());
  EXPECT_EQ(offered_step1, 2);  // refused, asked for, refused again: no third time
  EXPECT_NE(failure.find(ch::scene.name), std::string::npos) << failure;
  EXPECT_NE(failure.find("serial 1 was refused (step 1 is refused), asked for again, and refused again"), std::string::npos)
      << failure;
  EXPECT_EQ(taken, std::vector<std::int64_t>{0});
}

// Refused once only (as a forged copy would be): the serial is asked for
// again, and the run goes on.
TEST_F(Refusing, AMessageRefusedOnceIsTakenWhenItsTurnComesRight) {
  run(1);
  EXPECT_FALSE(eye.failed()) << failure;
  EXPECT_EQ(offered_step1, 2);
  EXPECT_EQ(taken, (std::vector<std::int64_t>{0, 1, 2}));
}

// ---- the bus below the edge: keys, names, overflows, bounds ---------------------------

struct EdgeOnTheBus : ::testing::Test {
  lcm::LCM lcm{"memq://"};
  RunConfig config = test::shippedConfig();
  ProtocolConfig protocol = test::shippedProtocol();
  std::string dir = test::tempDir("edge-key");
  Edge sender{lcm, quiet("environment"), "environment", protocol};
  Edge receiver{lcm, quiet("eye"), "eye", protocol};
  std::vector<std::int64_t> taken;

  void SetUp() override {
    sender.join("run-1", &config, {});
    receiver.join("run-1", &config, {});
    receiver.subscribe(ch::scene,
        [this](const scene_t& m) {
          taken.push_back(m.step);
          return Turn::take();
        },
        Scope::Run, Order::None);
  }
  std::shared_ptr<const BusKey> newKey(const std::string& name) {
    BusKey::writeNew(dir + "/" + name);
    return std::make_shared<const BusKey>(BusKey::fromFile(dir + "/" + name));
  }
  void pump() {
    while (lcm.handleTimeout(0) > 0) {
    }
  }
  static std::int64_t now() {
    return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
        .count();
  }
  Stamp fresh() { return {BusKey::newSession(), 0, now()}; }
  void raw(const std::string& channel, const std::vector<std::uint8_t>& b) {
    lcm.publish(channel, b.data(), static_cast<unsigned>(b.size()));
  }
};

TEST_F(EdgeOnTheBus, OnAKeyedBusOnlyMessagesWithTheKeysTagAreTaken) {
  const auto key = newKey("bus.key");
  sender.useKey(key);
  receiver.useKey(key);
  scene_t s0 = sceneOf("run-1", 0);
  sender.publish(ch::scene, s0);  // tagged
  pump();
  EXPECT_EQ(taken, std::vector<std::int64_t>{0});

  // A perfect message otherwise (fingerprint, run id, digest): untagged, tagged by another key,
  // or tagged for another channel.
  scene_t s1 = sceneOf("run-1", 1);
  const std::vector<std::uint8_t> plain = sealed(s1);
  raw(ch::scene.name, plain);
  raw(ch::scene.name, newKey("other.key")->tagged(ch::scene.name, plain.data(), plain.size(), fresh()));
  raw(ch::scene.name, key->tagged(ch::focus.name, plain.data(), plain.size(), fresh()));
  pump();
  EXPECT_EQ(taken, std::vector<std::int64_t>{0});
  EXPECT_EQ(receiver.drops().untagged, 3);
  EXPECT_EQ(receiver.drops().refused, 0) << "no untagged message reached the checks behind the tag";
  raw(ch::scene.name, key->tagged(ch::scene.name, plain.data(), plain.size(), fresh()));
  pump();
  EXPECT_EQ(taken, (std::vector<std::int64_t>{0, 1}));
}

// A passive listener samples a channel: while it does not take it, its messages are not handed to it (over
// udpm the kernel drops them); taken again, the next ones are. A channel not subscribed cannot be taken.
TEST_F(EdgeOnTheBus, AChannelNotTakenIsNotHandedOnAndIsTakenAgainWhenAskedFor) {
  scene_t s0 = sceneOf("run-1", 0), s1 = sceneOf("run-1", 1), s2 = sceneOf("run-1", 2);
  sender.publish(ch::scene, s0);
  pump();
  receiver.take(ch::scene.name, false);
  receiver.take(ch::scene.name, false);  // twice is once
  sender.publish(ch::scene, s1);
  pump();
  EXPECT_EQ(taken, std::vector<std::int64_t>{0});
  receiver.take(ch::scene.name, true);
  sender.publish(ch::scene, s2);
  pump();
  EXPECT_EQ(taken, (std::vector<std::int64_t>{0, 2}));
  EXPECT_THROW(receiver.take(ch::focus.name, true), std::logic_error);
}

// Freshness: a tagged message said again (the same bytes, a recording played back) is dropped and counted,
// before anything else of it is looked at; the sender's next message is taken.
TEST_F(EdgeOnTheBus, OnAKeyedBusAMessageSaidAgainIsDroppedAndCounted) {
  const auto key = newKey("bus.key");
  receiver.useKey(key);
  std::vector<std::vector<std::uint8_t>> sent;
  for (std::int64_t step = 0; step < 3; ++step) {
    scene_t s = sceneOf("run-1", step);
    const std::vector<std::uint8_t> plain = sealed(s);
    sent.push_back(key->tagged(ch::scene.name, plain.data(), plain.size(), {77, static_cast<std::uint64_t>(step), now()}));
  }
  raw(ch::scene.name, sent[0]);
  raw(ch::scene.name, sent[2]);
  raw(ch::scene.name, sent[0]);  // again
  raw(ch::scene.name, sent[1]);  // late, within the window: taken
  raw(ch::scene.name, sent[1]);  // again
  pump();
  EXPECT_EQ(taken, (std::vector<std::int64_t>{0, 2, 1}));
  EXPECT_EQ(receiver.drops().replayed, 2);
  EXPECT_EQ(receiver.drops().untagged + receiver.drops().refused, 0);
  // A sender not heard yet, whose message is older than protocol.freshness_ms: a recording's.
  scene_t old = sceneOf("run-1", 3);
  const std::vector<std::uint8_t> plain = sealed(old);
  raw(ch::scene.name, key->tagged(ch::scene.name, plain.data(), plain.size(),
                                  {78, 0, now() - protocol.freshness_ms - 1000}));
  pump();
  EXPECT_EQ(receiver.drops().replayed, 3);
  EXPECT_EQ(taken.size(), 3u);
}

TEST_F(EdgeOnTheBus, ATaggedMessageIsRefusedWhereThereIsNoKey) {
  sender.useKey(newKey("bus.key"));
  scene_t s0 = sceneOf("run-1", 0);
  sender.publish(ch::scene, s0);
  pump();
  EXPECT_TRUE(taken.empty());
  EXPECT_EQ(receiver.drops().refused, 1);
}

TEST_F(EdgeOnTheBus, ARunIdThatIsNoSafeNameIsDroppedBeforeDecoding) {
  Edge observer{lcm, quiet("viewer"), "viewer", protocol};
  std::vector<std::string> runs;
  observer.subscribe(ch::scene,
      [&](const scene_t& m) {
        runs.push_back(m.run_id);
        return Turn::take();
      },
      Scope::Any, Order::None);
  for (const std::string id : {"../../x", "a/b", "..", ".hidden", "ok-run"}) {
    scene_t s = sceneOf(id, 0);
    raw(ch::scene.name, sealed(s));
  }
  pump();
  EXPECT_EQ(runs, std::vector<std::string>{"ok-run"});
  EXPECT_EQ(observer.drops().refused, 4);
}

TEST_F(EdgeOnTheBus, AResendAskingFromTheLargestSerialIsAnsweredWithNothing) {
  scene_t s0 = sceneOf("run-1", 0);
  sender.publish(ch::scene, s0);
  sender.answerResends();
  pump();
  taken.clear();
  resend_t r;
  r.run_id = "run-1";
  r.step = 0;
  r.channel = ch::scene.name;
  r.requester = "test";
  r.config_digest = 0;  // the request the sender joined
  for (const auto& [first, last] : std::vector<std::pair<std::int64_t, std::int64_t>>{
           {INT64_MAX, INT64_MAX}, {INT64_MAX - 1, INT64_MAX}, {0, INT64_MAX}}) {
    r.first = first;
    r.last = last;
    raw(ch::resend.name, sealed(r));
  }
  pump();
  EXPECT_EQ(taken, std::vector<std::int64_t>{0}) << "serial 0 once (the request from 0), nothing beyond the history";
}

TEST_F(EdgeOnTheBus, AMessageLargerThanTheBusTakesIsNotSent) {
  config.protocol.bus.max_message_bytes = 10000;
  scene_t s = sceneOf("run-1", 0);
  s.data.assign(20000, 7);
  s.size = static_cast<int32_t>(s.data.size());
  try {
    sender.publish(ch::scene, s);
    ADD_FAILURE() << "a 20 KB message was sent on a bus of 10 KB messages";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("protocol.bus.max_message_bytes"), std::string::npos) << e.what();
  }
}

TEST_F(EdgeOnTheBus, ForgedProcessIdsCannotGrowWhatAReceiverRemembers) {
  Edge runner{lcm, quiet("runner"), "runner", protocol};
  int heard = 0;
  runner.subscribe(ch::status,
      [&](const process_status_t&) {
        ++heard;
        return Turn::take();
      },
      Scope::Any, Order::None);
  process_status_t st{};
  st.step = -1;
  st.process = "eye";
  st.beat = 1;
  st.state = process_status_t::WAITING;
  st.config_digest = 0;
  st.counts_config = 0;
  st.n_channels = 0;
  st.n_takes = 0;
  st.started = 0;
  st.n_copies = 0;
  const int forged = protocol.limits.peers * 3;
  for (int pid = 1; pid <= forged; ++pid) {
    st.pid = pid;
    raw(ch::status.name, sealed(st));
    pump();
  }
  EXPECT_EQ(heard, forged);
  EXPECT_EQ(runner.drops().peers_forgotten, forged - protocol.limits.peers);
}

// What paces a process's idle announcements (NodeBase): how long it usually waits, after publishing, for the
// next run message it takes. A message taken with nothing published before it, or after a wait in which the
// process announced its counts, does not count (a loss's wait would lengthen the next announcement's).
TEST(UsualWait, IsTheTimeFromAPublicationToTheNextRunMessageTakenUnlessAnnouncedIn) {
  using Clock = std::chrono::steady_clock;
  lcm::LCM lcm{"memq://"};
  RunConfig config = test::shippedConfig();
  ProtocolConfig protocol = test::shippedProtocol();
  Edge environment{lcm, quiet("environment"), "environment", protocol};
  Edge motivation{lcm, quiet("motivation"), "motivation", protocol};
  environment.join("run-1", &config, {});
  motivation.join("run-1", &config, {});
  int taken = 0;
  motivation.subscribe(ch::scene,
      [&](const scene_t&) {
        ++taken;
        return Turn::take();
      },
      Scope::Run, Order::Serial);
  auto deliver = [&](std::int64_t step) {
    scene_t s = sceneOf("run-1", step);
    environment.publish(ch::scene, s);
    while (lcm.handleTimeout(0) > 0) {
    }
  };
  auto decide = [&](std::int64_t step) {
    decision_t d{};
    d.run_id = "run-1";
    d.step = step;
    d.action = decision_t::NONE;
    motivation.publish(ch::decision, d);
    return Clock::now();
  };
  const auto elapse = [](Clock::time_point since, Clock::duration d) {  // the wait under test, by the clock
    while (Clock::now() - since < d) {
    }
  };
  const Clock::duration gap = std::chrono::milliseconds(2);

  deliver(0);
  EXPECT_EQ(motivation.usualWait(), Clock::duration::zero()) << "nothing was published before it";
  elapse(decide(0), gap);
  deliver(1);
  const Clock::duration first = motivation.usualWait();
  EXPECT_GE(first, gap / 8) << "a moving average (1/8) of waits of at least " << gap.count() << " ns";
  deliver(2);
  EXPECT_EQ(motivation.usualWait(), first) << "a second message after one publication is no wait";
  const Clock::time_point decided = decide(1);
  motivation.waitAnnounced();
  elapse(decided, gap);
  deliver(3);
  EXPECT_EQ(motivation.usualWait(), first) << "a wait in which the process announced is not counted";
  EXPECT_EQ(taken, 4);
}

TEST(Bus, AUdpmUrlGetsTheBusBoundsUnlessItSetsThemAndOtherProvidersAreRefused) {
  const BusConfig bus = test::shippedProtocol().bus;
  EXPECT_EQ(busUrl("udpm://239.255.76.67:7700", bus),
            "udpm://239.255.76.67:7700?max_message_size=" + std::to_string(bus.max_message_bytes) +
                "&fragment_buffer_size=" + std::to_string(bus.fragment_bytes) +
                "&fragment_timeout_ms=" + std::to_string(bus.fragment_timeout_ms) +
                "&receive_queue_size=" + std::to_string(bus.queue_bytes));
  const std::string own = busUrl("udpm://239.255.76.67:7700?ttl=0&max_message_size=5000", bus);
  EXPECT_NE(own.find("?ttl=0&max_message_size=5000&fragment_buffer_size="), std::string::npos) << own;
  EXPECT_EQ(own.find("max_message_size=" + std::to_string(bus.max_message_bytes)), std::string::npos) << own;
  EXPECT_EQ(busUrl("memq://", bus), "memq://");
  for (const std::string url : {"mpudpm://239.255.76.67:7700", "tcpq://localhost:7700", "file:///tmp/x.lcm"}) {
    try {
      openBus(url, bus);
      ADD_FAILURE() << url << " was opened";
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find("udpm://"), std::string::npos) << e.what();
    }
  }
}

// ---- what the edge says of what it drops ------------------------------------------------

using test::Said;

// Ten thousand drops of three kinds (numbers in their reasons differ: they are of one kind) are a handful of
// lines, and every drop is in them.
TEST(DropLog, AFloodIsSaidInAFewLinesAndEveryDropIsCounted) {
  Said said;
  DropLog drops(said.log);
  for (int i = 0; i < 10000; ++i) {
    if (i % 3 == 0) drops.drop("SCENE", "field prev_digest does not follow the channel's message " + std::to_string(i));
    if (i % 3 == 1) drops.drop("FOCUS", "field digest does not match the message (corrupted or forged)");
    if (i % 3 == 2) drops.drop("STATUS", "a message said again: counter " + std::to_string(i) + " taken already");
  }
  drops.flush();
  EXPECT_LE(said.lines().size(), 3u * DropLog::kSaidPerKind + 2) << said.text.str();
  EXPECT_EQ(said.accounted(), 10000) << said.text.str();
  EXPECT_NE(said.text.str().find("(more drops are counted and summarised)"), std::string::npos);
  EXPECT_NE(said.text.str().find("like \"SCENE: field prev_digest does not follow"), std::string::npos) << said.text.str();
}

// A kind not seen before is said at once, even in the middle of a flood of another.
TEST(DropLog, ANewKindIsSaidAtOnceDuringAFlood) {
  Said said;
  DropLog drops(said.log);
  for (int i = 0; i < 500; ++i) drops.drop("SCENE", "field step " + std::to_string(i) + " is in the past");
  drops.drop("RUN_CONTROL", "a command for another request of run 'r'");
  EXPECT_NE(said.text.str().find("RUN_CONTROL: dropped message: a command for another request"), std::string::npos)
      << said.text.str();
}

// Through the edge: thousands of malformed messages on a run channel, a few dozen lines at most (a replayed
// recording once wrote a line for each of 12,700 events, in every process).
TEST_F(EdgeOnTheBus, ThousandsOfBadMessagesCostAFewLines) {
  Said said;
  std::int64_t drops = 0;
  {
    Edge eye{lcm, said.log, "eye", protocol};
    eye.join("run-1", &config, {});
    eye.subscribe(ch::scene, [](const scene_t&) { return Turn::take(); }, Scope::Run, Order::Serial);
    for (int i = 0; i < 3000; ++i) {
      scene_t s = sceneOf("run-1", i % 7);
      s.serial = i % 5;
      s.prev_digest = i;  // follows no chain
      auto bytes = sealed(s);
      if (i % 2) bytes[bytes.size() - 1] ^= 1;  // and half of them damaged
      lcm.publish(ch::scene.name, bytes.data(), static_cast<unsigned>(bytes.size()));
      pump();
    }
    drops = eye.drops().refused;
  }  // the edge's end says the rest
  EXPECT_GE(drops, 1500);  // (those beyond the next serial are gaps, asked for, not drops)
  EXPECT_LE(said.lines().size(), 40u) << said.text.str();
  EXPECT_EQ(said.accounted(), drops) << said.text.str();
}

}  // namespace
}  // namespace afford
