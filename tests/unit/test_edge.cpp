// The message edge's handling of a handler that refuses: a refused message is
// expected again (it may have been a forged one); the same message refused
// again, once asked for, fails the run naming the channel instead of asking
// for it without end.
#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>

#include <string>

#include "afford/channels.hpp"
#include "afford/edge.hpp"
#include "afford/image.hpp"
#include "afford/scene_t.hpp"
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
    environment.join("run-1", &config);
    eye.join("run-1", &config);
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
    eye.subscribe<scene_t>(
        channel::kScene,
        [this, refusals](const scene_t& s) {
          if (s.step == 1 && offered_step1++ < refusals) return Turn::refuse("step 1 is refused");
          taken.push_back(s.step);
          return Turn::take();
        },
        Scope::Run, Order::Serial);
    for (std::int64_t step : {0, 1, 2}) {
      scene_t s = sceneOf("run-1", step);
      environment.publish(channel::kScene, s);
    }
    pump();
  }
};

TEST_F(Refusing, TheSameMessageRefusedAgainFailsTheRunNamingTheChannel) {
  run(1000);
  ASSERT_TRUE(eye.failed());
  EXPECT_EQ(offered_step1, 2);  // refused, asked for, refused again: no third time
  EXPECT_NE(failure.find(channel::kScene), std::string::npos) << failure;
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

}  // namespace
}  // namespace afford
