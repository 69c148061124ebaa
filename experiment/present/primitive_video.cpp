#include "experiment/present/primitive_video.hpp"

#include <fmt/printf.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <vector>

#include "afford/auth.hpp"
#include "afford/config.hpp"
#include "afford/decode.hpp"
#include "afford/decision_t.hpp"
#include "afford/image.hpp"
#include "afford/process_main.hpp"
#include "afford/protocol.hpp"
#include "afford/scene_t.hpp"
#include "environment/table_world.hpp"
#include "environment/world.hpp"
#include "experiment/present/encoder.hpp"
#include "experiment/replay/replay.hpp"

namespace afford {

namespace {

constexpr int kScale = 2;  // each camera's image drawn twice its size in the video

// The run's messages of one channel, the first of each step (a repeat, sent again after a loss, is the same).
template <class Msg>
std::map<std::int64_t, Msg> byStep(const RunEvents& run, const Channel<Msg>& channel, const BoundsContext& ctx,
                                   bool (*keep)(const Msg&)) {
  std::map<std::int64_t, Msg> out;
  for (const LogEvent& e : run.events) {
    if (e.channel != channel.name) continue;
    Msg m;
    std::string why;
    if (!decodeChecked(e.data.data(), e.data.size(), ctx, m, why) || m.run_id != run.config.run_id || !keep(m)) continue;
    out.emplace(m.step, std::move(m));
  }
  return out;
}

// The steps that acted nearest `step`, for a message naming them.
std::string actedNear(const std::map<std::int64_t, decision_t>& decisions, std::int64_t step) {
  std::vector<std::int64_t> acted;
  for (const auto& [s, d] : decisions)
    if (d.acted) acted.push_back(s);
  if (acted.empty()) return "no step of the run acted";
  std::sort(acted.begin(), acted.end(), [&](std::int64_t a, std::int64_t b) {
    return std::llabs(a - step) != std::llabs(b - step) ? std::llabs(a - step) < std::llabs(b - step) : a < b;
  });
  acted.resize(std::min<std::size_t>(acted.size(), 5));
  std::sort(acted.begin(), acted.end());
  std::string out = "steps that acted near it:";
  for (std::int64_t s : acted) out += " " + std::to_string(s);
  return out;
}

std::optional<std::pair<double, double>> placeOf(const RunConfig& c, const decision_t& d) {
  if (takesPlace(c.world.kind, d.action) && d.target_x >= 0.0 && d.target_y >= 0.0)
    return std::make_pair(d.target_x, d.target_y);
  return std::nullopt;
}

// One frame: the top camera and the side view, the hand drawn in both, over a line saying what is shown.
cv::Mat frameOf(table::TableCamera& top, table::TableCamera& side, const table::TablePhysics& physics,
                const std::string& caption) {
  cv::Mat both, big, bgr;
  cv::hconcat(top.rgb(physics), side.rgb(physics), both);
  cv::resize(both, big, cv::Size(), kScale, kScale, cv::INTER_LINEAR);
  cv::cvtColor(big, bgr, cv::COLOR_RGB2BGR);
  cv::Mat frame(bgr.rows + 36, bgr.cols, CV_8UC3, cv::Scalar(34, 34, 34));
  bgr.copyTo(frame(cv::Rect(0, 0, bgr.cols, bgr.rows)));
  cv::putText(frame, caption, cv::Point(10, bgr.rows + 25), cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(230, 230, 230),
              1, cv::LINE_AA);
  return frame;
}

}  // namespace

PrimitiveVideoResult renderPrimitive(const PrimitiveVideoOptions& o, spdlog::logger& log) {
  if (o.step < 0) throw std::runtime_error("--primitive " + std::to_string(o.step) + ": a step, 0 or more");
  VideoFile file(o.out, o.ffmpeg, o.fps, "afford render");
  const std::shared_ptr<const BusKey> key = o.bus_key.empty() ? nullptr : busKeyFrom(o.bus_key);
  const RunEvents run = readRunEvents(o.log, o.run_id, log, key.get());
  const std::string where = o.log.string() + ": run '" + run.config.run_id + "'";
  RunConfig config;
  try {
    config = parseRunConfigText(run.config.config_yaml);
  } catch (const std::exception& e) {
    throw std::runtime_error(where + ": the configuration in its RUN_CONFIG is refused: " + e.what());
  }
  if (config.world.kind != WorldKind::Table)
    throw std::runtime_error(where + " is of the paper's world (world.kind: grid), whose actions are routines, not "
                             "motor primitives: --primitive draws a table run's (world.kind: table)");
  const BoundsContext ctx{&config.protocol, &config};
  const bool extrinsic = config.phase == Phase::Extrinsic;
  // The extrinsic phase executes the planner's acted decisions; the others every step's, in step order.
  const auto decisions = byStep<decision_t>(run, ch::decision, ctx, [](const decision_t&) { return true; });
  const auto it = decisions.find(o.step);
  if (it == decisions.end())
    throw std::runtime_error(where + ": no DECISION of step " + std::to_string(o.step) + " in the log (" +
                             actedNear(decisions, o.step) + ")");
  const decision_t& chosen = it->second;
  if (!chosen.acted)
    throw std::runtime_error(where + ": at step " + std::to_string(o.step) + " the agent did not act, so no primitive "
                             "ran (" + actedNear(decisions, o.step) + ")");
  // The scene the run published after the action: the simulation's end must be it.
  const std::int64_t scene_step = extrinsic ? o.step : o.step + 1;
  const auto scenes = byStep<scene_t>(run, ch::scene, ctx, [](const scene_t& s) { return s.cause == scene_t::CAUSE_ACTION; });
  const auto logged = scenes.find(scene_step);
  if (logged == scenes.end())
    throw std::runtime_error(where + ": the log holds no SCENE after the action of step " + std::to_string(o.step) +
                             " to check the simulation against");

  std::unique_ptr<SimWorld> world = makeWorld(config);
  auto& table = dynamic_cast<TableWorld&>(*world);
  PrimitiveVideoResult r;
  r.run_id = run.config.run_id;
  for (std::int64_t s = 0; s < o.step; ++s) {  // the environment's part of the run, again
    if (stopRequested()) throw std::runtime_error("interrupted: " + o.out.string() + " not written");
    const auto d = decisions.find(s);
    if (d == decisions.end()) {
      if (extrinsic) continue;  // an iteration without a decision: nothing done
      throw std::runtime_error(where + ": the log lacks the DECISION of step " + std::to_string(s) +
                               ", so the run cannot be simulated again up to step " + std::to_string(o.step));
    }
    if (d->second.acted) {
      world->execute(s, d->second.action, d->second.x, d->second.y, placeOf(config, d->second));
      ++r.replayed;
    }
    if (!extrinsic && s + 1 < config.steps) world->introduceObjectsAt(s + 1);
    if ((s + 1) % 500 == 0) log.info("simulating the run again: step {} of {}", s + 1, o.step);
  }

  const int object = table.objectAt(chosen.x, chosen.y);
  r.object = object >= 0 ? config.table.spec.objects[static_cast<std::size_t>(object)].name : "none";
  r.action = std::string(actionName(config.world.kind, chosen.action));
  const std::string what = "step " + std::to_string(o.step) + ": " + r.action + " " + r.object;
  table::TableCamera top(table.physics(), {true, false}), side(table.physics(), {true, true});
  const int every = std::max(1, static_cast<int>(std::lround(1.0 / (o.fps * config.table.spec.timestep))));
  auto frame = [&](const std::string& caption) {
    if (stopRequested()) throw std::runtime_error("interrupted: " + o.out.string() + " not written");
    file.write(frameOf(top, side, table.physics(), caption));
    ++r.frames;
  };
  for (int i = 0; i < o.fps / 2; ++i) frame(what);  // half a second of the scene before the action
  std::int64_t steps = 0;
  table.observe([&](const table::TablePhysics& p) {
    steps += every;
    frame(what + fmt::sprintf("   t = %.2f s", steps * p.spec().timestep));
  }, every);
  const ActionOutcome out = world->execute(o.step, chosen.action, chosen.x, chosen.y, placeOf(config, chosen));
  table.observe(nullptr, 1);
  r.succeeded = out.succeeded;
  r.physics_steps = table.lastPrimitive().physics_steps;

  const scene_t& s = logged->second;
  const cv::Mat published = decodeScene(s.data, s.width, s.height), simulated = world->render();
  if (!sameImage(published, simulated)) {
    cv::Mat diff;
    cv::absdiff(published, simulated, diff);
    throw std::runtime_error(
        where + ": simulated again, the action of step " + std::to_string(o.step) + " ends in another scene than the "
        "run published (" + std::to_string(cv::countNonZero(diff.reshape(1))) + " bytes differ): this build or its "
        "MuJoCo is not the run's, so its primitive cannot be shown; " + o.out.string() + " not written");
  }
  const std::string verdict = what + (out.succeeded ? "   goal reached" : "   goal not reached");
  for (int i = 0; i < o.fps; ++i) frame(verdict);  // a second of the end, its verdict said
  file.finish();
  r.width = file.width(), r.height = file.height();
  return r;
}

}  // namespace afford
