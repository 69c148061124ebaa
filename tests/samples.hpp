// Realistic messages of every type, from a run of the shipped base experiment
// (IMP, seed 1): every array and string filled, every value one the run
// sends. Shared by tests/unit/test_wire.cpp and the fuzz seeds (tests/fuzz).
// The digest is a placeholder: afford::sealed() sets the real one.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "afford/actions.hpp"
#include "afford/protocol.hpp"
#include "afford/checks.hpp"
#include "afford/image.hpp"
#include "tests/support.hpp"

namespace afford::test {

// The run the samples belong to.
inline const RunConfig& sampleConfig() {
  static const RunConfig c = [] {
    RunConfig r = shippedConfig();
    r.planner.max_depth = 2;  // so that a query may carry an imagined action (forward_query_t.prefix)
    return r;
  }();
  return c;
}

inline const std::string kSampleRunId = "20240501-120000-base-IMP-s1";

inline std::vector<std::uint8_t> focusImage(int side) {
  std::vector<std::uint8_t> image(static_cast<std::size_t>(3 * side * side));
  for (std::size_t i = 0; i < image.size(); ++i) image[i] = (i / 3) % 7 == 0 ? 255 : 0;
  return image;
}
inline std::vector<std::uint8_t> focusImage() { return focusImage(sampleConfig().eye.focus_side); }

inline trained_t sampleTrained() {
  trained_t t;
  t.run_id = kSampleRunId;
  t.step = 41;
  t.action = kTurnRed;
  t.affordance = true;
  t.affordance_before = 0.42;
  t.affordance_after = 0.47;
  t.learning_progress = 0.01;
  t.effect_trained = true;
  return t;
}

inline affordance_table_t sample(const affordance_table_t*) {
  affordance_table_t m;
  m.run_id = kSampleRunId;
  m.step = 1000;
  m.serial = 9;
  m.prev_digest = 0x5eed0000 + 9;
  for (std::size_t o = 0; o < sampleConfig().world.objects.size(); ++o)
    m.affordance.push_back({0.9, 0.1 * static_cast<double>(o % 3), 0.5, 0.05});
  m.n_objects = static_cast<int32_t>(m.affordance.size());
  m.n_actions = kNumActions;
  m.digest = 0x1234;
  return m;
}

inline decision_t sample(const decision_t*) {
  decision_t m;
  m.run_id = kSampleRunId;
  m.step = 42;
  m.serial = 42;
  m.prev_digest = 0x5eed0000 + 42;
  m.acted = true;
  m.action = decision_t::MOVE;
  m.x = 0.3;
  m.y = 0.6;
  m.target_x = -1;
  m.target_y = -1;
  m.motivation = 0.8;
  m.threshold = 0.7;
  m.revisit = false;
  m.seq = 0;
  m.digest = 0x1234;
  return m;
}

inline effect_t sample(const effect_t*) {
  effect_t m;
  m.run_id = kSampleRunId;
  m.step = 42;
  m.serial = 17;
  m.prev_digest = 0x5eed0000 + 17;
  m.action = decision_t::TURN_GREEN;
  m.target_x = m.target_y = -1;
  m.before_x = m.after_x = 0.3;
  m.before_y = m.after_y = 0.6;
  m.image_change = 0.2;
  m.position_change = 0;
  m.affordance = true;
  m.side = sampleConfig().eye.focus_side;
  m.image = focusImage();
  m.size = static_cast<int32_t>(m.image.size());
  m.digest = 0x1234;
  return m;
}

inline extrinsic_result_t sample(const extrinsic_result_t*) {
  extrinsic_result_t m;
  m.run_id = kSampleRunId + "-stack";
  m.step = 12;
  m.serial = 0;
  m.prev_digest = 0x5eed0000 + 0;
  m.scenario = "stack";
  m.success = true;
  m.completion = 12;
  m.attempts = 3;
  m.utility = 1.5;
  m.sub_goals = {{0.2, 0.3, 5, 8, 2, 1}, {0.7, 0.4, 7, 4, 1, 1}};
  m.n_sub_goals = static_cast<int32_t>(m.sub_goals.size());
  m.digest = 0x1234;
  return m;
}

inline focus_t sample(const focus_t*) {
  focus_t m;
  m.run_id = kSampleRunId;
  m.step = 42;
  m.serial = 43;
  m.prev_digest = 0x5eed0000 + 43;
  m.kind = focus_t::GOAL_DIFF;  // the kind with differences (top-down attention)
  m.seq = 3;
  m.x = 0.3;
  m.y = 0.6;
  m.side = sampleConfig().eye.focus_side;
  m.image = focusImage();
  m.size = static_cast<int32_t>(m.image.size());
  m.diff_x = {0.2, 0.7};
  m.diff_y = {0.5, 0.35};
  m.diff_in = {focus_t::DIFF_GOAL, focus_t::DIFF_SCENE};
  m.diff_image = {focusImage(), focusImage()};
  m.n_diffs = static_cast<int32_t>(m.diff_x.size());
  m.digest = 0x1234;
  return m;
}

inline forward_prediction_t sample(const forward_prediction_t*) {
  forward_prediction_t m;
  m.run_id = kSampleRunId + "-stack";
  m.step = 3;
  m.serial = 5;
  m.prev_digest = 0x5eed0000 + 5;
  m.seq = 6;
  m.actions = {kMove, kTurnBlue};  // the candidates the query asked for
  m.n_actions = static_cast<int32_t>(m.actions.size());
  const std::vector<std::uint8_t> image = focusImage();
  m.size = static_cast<int32_t>(image.size());
  for (std::size_t a = 0; a < m.actions.size(); ++a) {
    m.what.emplace_back(image.size());
    for (std::size_t i = 0; i < image.size(); ++i) m.what[a][i] = static_cast<float>(image[i]) / 255.0f;
  }
  m.where_x = {0.5, 0.3};
  m.where_y = {0.4, 0.6};
  m.input_affordance = {0.9, 0.1, 0.8, 0.2};  // the query's image was imagined
  m.n_input = static_cast<int8_t>(m.input_affordance.size());
  m.digest = 0x1234;
  return m;
}

inline forward_query_t sample(const forward_query_t*) {
  forward_query_t m;
  m.run_id = kSampleRunId + "-stack";
  m.step = 3;
  m.serial = 5;
  m.prev_digest = 0x5eed0000 + 5;
  m.seq = 6;
  m.x = 0.3;
  m.y = 0.6;
  m.target_x = 0.5;
  m.target_y = 0.4;
  m.image = focusImage();
  m.size = static_cast<int32_t>(m.image.size());
  m.actions = {kMove, kTurnBlue};
  m.n_actions = static_cast<int32_t>(m.actions.size());
  m.prefix = {kTurnGreen};  // the object of `image` is imagined after turning it green
  m.n_prefix = static_cast<int8_t>(m.prefix.size());
  m.digest = 0x1234;
  return m;
}

inline goal_t sample(const goal_t*) {
  goal_t m;
  m.run_id = kSampleRunId;
  m.step = 12;
  m.serial = 3;
  m.prev_digest = 0x5eed0000 + 3;
  m.id = 3;
  m.module = goal_t::COLOUR;
  m.object_x = 0.25;
  m.object_y = 0.75;
  m.x = 0.25;
  m.y = 0.75;
  m.size = 21 * 21 * 3;
  m.image.assign(static_cast<std::size_t>(m.size), 0);
  for (std::size_t i = 0; i < m.image.size(); i += 3) m.image[i] = 200;
  m.action = -1;
  m.budget = 4;
  m.digest = 0x1234;
  return m;
}

inline goal_result_t sample(const goal_result_t*) {
  goal_result_t m;
  m.run_id = kSampleRunId;
  m.step = 14;
  m.serial = 3;
  m.prev_digest = 0x5eed0000 + 3;
  m.id = 3;
  m.module = goal_t::COLOUR;
  m.reached = true;
  m.distance = 0.004;
  m.actions = 2;
  m.planned = true;
  m.effects = 9;
  m.focus_serial = 40;
  m.forward_serial = 11;
  m.seq = 52;
  m.digest = 0x1234;
  return m;
}

inline look_t sample(const look_t*) {
  look_t m;
  m.run_id = kSampleRunId + "-stack";
  m.step = 3;
  m.serial = 7;
  m.prev_digest = 0x5eed0000 + 7;
  m.seq = 7;
  m.kind = focus_t::SCENE_AT;
  m.scene = 2;
  m.x = 0.5;
  m.y = 0.4;
  m.digest = 0x1234;
  return m;
}

inline object_probe_t sample(const object_probe_t*) {
  object_probe_t m;
  m.run_id = kSampleRunId;
  m.step = 0;
  m.serial = 0;
  m.prev_digest = 0x5eed0000 + 0;
  for (const ObjectSpec& o : sampleConfig().world.objects) {
    m.names.push_back(o.name);
    m.images.push_back(focusImage());
  }
  m.n_objects = static_cast<int32_t>(m.names.size());
  m.size = static_cast<int32_t>(m.images.front().size());
  m.digest = 0x1234;
  return m;
}

inline prediction_t sample(const prediction_t*) {
  prediction_t m;
  m.run_id = kSampleRunId;
  m.step = 42;
  m.serial = 42;
  m.prev_digest = 0x5eed0000 + 42;
  m.x = 0.3;
  m.y = 0.6;
  m.n_actions = kNumActions;
  m.affordance = {0.9, 0.2, 0.6, 0.1};
  m.learning_progress = {0.01, -0.02, 0.0, 0.03};
  m.look = 3;
  m.n_tried = kNumActions;
  m.tried_ago = {-1, 12, 0, 40};
  m.trained = {sampleTrained()};
  m.n_trained = 1;
  m.digest = 0x1234;
  return m;
}

inline process_status_t sample(const process_status_t*) {
  process_status_t m{};
  m.run_id = kSampleRunId;
  m.step = 42;
  m.process = "logger";
  m.pid = 4242;
  m.beat = 12;
  m.state = process_status_t::RUNNING;
  m.config_digest = 0x0c0ffee;
  m.detail = "logs/" + kSampleRunId;
  m.stuck = "DECISION serial 44 (published by motivation): field prev_digest does not follow, 3 times";
  m.counts_run = kSampleRunId;
  m.counts_config = 0x0c0ffee;
  m.channels = {ch::scene.name, ch::focus.name, ch::prediction.name};
  m.counts = {12, 43, 43};
  m.held_from = {0, 0, 0};
  m.n_channels = static_cast<int32_t>(m.channels.size());
  m.takes = {ch::decision.name, ch::effect.name};
  m.takes_from = {40, 12};
  m.n_takes = static_cast<int32_t>(m.takes.size());
  m.host = "lab-1";
  m.started = 1700000000000000;
  m.copies = {"4343@lab-1/1700000000000001"};
  m.n_copies = static_cast<int32_t>(m.copies.size());
  m.digest = 0x1234;
  return m;
}

inline resend_t sample(const resend_t*) {
  resend_t m;
  m.run_id = kSampleRunId;
  m.step = 0;
  m.channel = ch::focus.name;
  m.first = 40;
  m.last = 43;
  m.requester = "motivation";
  m.config_digest = 0x0c0ffee;
  m.digest = 0x1234;
  return m;
}

inline run_config_t sample(const run_config_t*) {
  run_config_t m;
  m.run_id = kSampleRunId;
  m.step = 0;
  m.request = 0x7e9;
  m.seed = 1;
  m.experiment = "base";
  m.system = "IMP";
  m.config_yaml = test::shippedConfigYaml("base", System::IMP, 1, 1000);
  m.digest = 0x1234;
  return m;
}

inline run_control_t sample(const run_control_t*) {
  run_control_t m;
  m.run_id = kSampleRunId;
  m.step = 0;
  m.command = run_control_t::START;
  m.config_digest = 0x0c0ffee;
  m.digest = 0x1234;
  return m;
}

inline run_result_t sample(const run_result_t*) {
  run_result_t m;
  m.run_id = kSampleRunId;
  m.step = 1000;
  m.serial = 0;
  m.prev_digest = 0x5eed0000 + 0;
  m.weights_checksum = "9ac0f1d2e3b4a5c6";
  m.checkpoint = "logs/" + kSampleRunId + "/predictors.ckpt";
  m.n_actions = kNumActions;
  m.actions_executed = {120, 80, 75, 90};
  m.successes = {60, 40, 20, 30};
  m.looks = 9;
  m.replayed = 5600;
  m.replayed_effects = 300;
  m.revisits = 40;
  m.trained = {sampleTrained()};
  m.n_trained = 1;
  m.digest = 0x1234;
  return m;
}

inline scene_t sample(const scene_t*) {
  const RunConfig& c = sampleConfig();
  cv::Mat scene = blankScene(c.world.size_px);
  for (const ObjectSpec& o : c.world.objects)
    paintObject(scene, o.shape, o.colour, o.x, o.y, c.world);
  scene_t m;
  m.run_id = kSampleRunId;
  m.step = 0;
  m.serial = 0;
  m.prev_digest = 0x5eed0000 + 0;
  m.cause = scene_t::CAUSE_START;
  m.scan = true;
  m.changes_next = false;
  m.action = -1;
  m.action_target_x = m.action_target_y = -1;
  m.goal_distance = m.goal_utility = -1;
  m.width = m.height = c.world.size_px;
  m.encoding = scene_t::ENCODING_ZLIB_RGB8;
  m.data = encodeScene(scene);
  m.size = static_cast<int32_t>(m.data.size());
  for (const ObjectSpec& o : c.world.objects) {
    m.object_x.push_back(o.x);
    m.object_y.push_back(o.y);
  }
  m.n_objects = static_cast<int16_t>(m.object_x.size());
  m.digest = 0x1234;
  return m;
}

// The sample of type Msg.
template <class Msg>
Msg sample() {
  return sample(static_cast<const Msg*>(nullptr));
}

}  // namespace afford::test
