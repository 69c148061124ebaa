// afford-viewer: watches a run and draws it (viewer.hpp): the scene with the
// gaze box (where the eye looked last: a scan, or after an action's effect), the goal image with the inner eye's focus, the focus image, the
// sub-goal, the affordance bars of the focused object, and the motivation and
// threshold traces. A passive listener: it publishes nothing and no run waits
// for it. With --png DIR it writes the same frames as PNG files, no display.
#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>
#include <opencv2/highgui.hpp>
#include <opencv2/imgcodecs.hpp>
#include <yaml-cpp/yaml.h>

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "afford/protocol.hpp"
#include "afford/decision_t.hpp"
#include "afford/effect_t.hpp"
#include "afford/focus_t.hpp"
#include "afford/image.hpp"
#include "afford/logging.hpp"
#include "afford/bus.hpp"
#include "afford/edge.hpp"
#include "afford/node.hpp"
#include "afford/process_main.hpp"
#include "afford/prediction_t.hpp"
#include "afford/run_config_t.hpp"
#include "afford/scene_t.hpp"
#include "viewer/viewer.hpp"

namespace {

// What the viewer hears, through the edge (afford/edge.hpp): decoded, checked,
// of the run shown (the last RUN_CONFIG's; any run until one is heard), each
// channel in serial order (a gap is skipped: the viewer asks for nothing).
struct Listener {
  afford::Viewer& viewer;
  spdlog::logger& log;
  afford::Edge& edge;
  afford::RunConfig config;  // of the run shown
  std::string shown;         // its id

  afford::Turn onConfig(const afford::run_config_t& m) {
    try {
      config = afford::parseRunConfigText(m.config_yaml);
    } catch (const std::exception& e) {
      return afford::Turn::refuse(std::string("its configuration is refused: ") + e.what());
    }
    edge.join(m.run_id, &config);
    if (m.run_id == shown) return afford::Turn::take();  // the runner says a run's configuration more than once
    shown = m.run_id;
    viewer.onRun(m.run_id, std::string(afford::nameOf(afford::kPhaseNames, config.phase)) + " " +
                               m.experiment + " " + m.system);
    log.info("showing run '{}'", m.run_id);
    return afford::Turn::take();
  }
  afford::Turn onScene(const afford::scene_t& m) {
    try {
      viewer.onScene(m.step, afford::decodeScene(m.data, m.width, m.height), m.cause == afford::scene_t::CAUSE_GOAL);
    } catch (const std::exception& e) {
      return afford::Turn::refuse(e.what());
    }
    return afford::Turn::take();
  }
  afford::Turn onFocus(const afford::focus_t& m) {
    viewer.onFocus(m.step, m.image, m.side, m.x, m.y, m.kind == afford::focus_t::GOAL_SCAN);
    return afford::Turn::take();
  }
  afford::Turn onPrediction(const afford::prediction_t& m) {
    viewer.onPrediction(m.step, {m.affordance[0], m.affordance[1], m.affordance[2], m.affordance[3]});
    return afford::Turn::take();
  }
  afford::Turn onEffect(const afford::effect_t& m) {  // the gaze after the change-driven scan
    viewer.onFocus(m.step, m.image, m.side, m.after_x, m.after_y, false);
    return afford::Turn::take();
  }
  afford::Turn onGoal(const afford::goal_t& m) {
    viewer.onGoal(m.step, m.id, goalModule(m.module), m.image, config.eye.focus_side, m.x, m.y);
    return afford::Turn::take();
  }
  afford::Turn onGoalResult(const afford::goal_result_t& m) {
    viewer.onGoalResult(m.step, m.id, goalModule(m.module), m.reached);
    return afford::Turn::take();
  }
  static std::string goalModule(int module) {
    static const char* names[] = {"explore", "colour", "move", "colour and place"};
    return module >= 0 && module < 4 ? names[module] : "?";
  }
  afford::Turn onDecision(const afford::decision_t& m) {
    viewer.onDecision(m.step, m.acted, m.action, m.motivation, m.threshold);
    return afford::Turn::take();
  }
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"afford viewer: watch a run (scene, gaze, goal, focus, affordances, motivation)", "afford-viewer"};
  std::string url = "udpm://239.255.76.67:7667?ttl=0", png_dir, level = "info";
  std::int64_t every = 10, max_frames = 0;
  app.add_option("--lcm-url", url, "LCM provider URL of the run")->capture_default_str();
  app.add_option("--png", png_dir, "write frames as PNG files into this folder instead of showing a window");
  app.add_option("--every", every, "with --png: a frame every N steps")->capture_default_str()->check(CLI::PositiveNumber);
  app.add_option("--max-frames", max_frames, "with --png: stop after this many frames (0: never)")->capture_default_str();
  app.add_option("--log-level", level, "trace, debug, info, warn, error or off")->capture_default_str();
  std::string config_dir = afford::defaultConfigDir();
  app.add_option("--config-dir", config_dir, "folder whose defaults.yaml gives what is accepted before a run is heard")
      ->capture_default_str();
  std::string key_file;
  app.add_option("--bus-key", key_file, "key file of a keyed bus (default: the file $AFFORD_BUS_KEY names)");
  CLI11_PARSE(app, argc, argv);
  auto log = afford::makeLogger("viewer", level);
  afford::ProtocolConfig protocol;
  try {
    protocol = afford::loadProtocol(config_dir);
  } catch (const std::exception& e) {
    log->error("--config-dir: {}", e.what());
    return 2;
  }
  std::shared_ptr<const afford::BusKey> key;
  std::unique_ptr<lcm::LCM> bus;
  try {
    key = afford::busKeyFrom(key_file);
    bus = afford::openBus(url, protocol.bus);
  } catch (const std::exception& e) {
    log->error("{}", e.what());
    return 1;
  }
  lcm::LCM& lcm = *bus;
  afford::installStopHandlers();
  if (!png_dir.empty()) std::filesystem::create_directories(png_dir);
  afford::Viewer viewer;
  afford::Edge edge(lcm, log, "viewer", protocol);
  edge.useKey(key);
  edge.warnOtherRuns(false);
  Listener listener{viewer, *log, edge, {}, {}};
  using afford::Order;
  using afford::Scope;
  edge.subscribe(afford::ch::runConfig, [&](const afford::run_config_t& m) { return listener.onConfig(m); }, Scope::Any,
      Order::None);
  edge.subscribe(afford::ch::scene, [&](const afford::scene_t& m) { return listener.onScene(m); }, Scope::RunOrAny,
      Order::Follow);
  edge.subscribe(afford::ch::focus, [&](const afford::focus_t& m) { return listener.onFocus(m); }, Scope::RunOrAny,
      Order::Follow);
  edge.subscribe(afford::ch::prediction, [&](const afford::prediction_t& m) { return listener.onPrediction(m); },
      Scope::RunOrAny, Order::Follow);
  edge.subscribe(afford::ch::decision, [&](const afford::decision_t& m) { return listener.onDecision(m); }, Scope::RunOrAny,
      Order::Follow);
  edge.subscribe(afford::ch::effect, [&](const afford::effect_t& m) { return listener.onEffect(m); }, Scope::RunOrAny,
      Order::Follow);
  edge.subscribe(afford::ch::goal, [&](const afford::goal_t& m) { return listener.onGoal(m); }, Scope::RunOrAny,
      Order::Follow);
  edge.subscribe(afford::ch::goalResult, [&](const afford::goal_result_t& m) { return listener.onGoalResult(m); },
      Scope::RunOrAny, Order::Follow);
  log->info("watching {}{}", url, png_dir.empty() ? "" : ", frames to " + png_dir);

  std::int64_t written = 0, last_frame_step = -1;
  std::string last_run;
  auto last_show = std::chrono::steady_clock::now();
  while (!afford::stopRequested()) {
    afford::pumpBus(lcm, 20);
    if (!png_dir.empty()) {
      if (edge.run() != last_run) last_run = edge.run(), last_frame_step = -1;
      if (viewer.step() >= 0 && (last_frame_step < 0 || viewer.step() - last_frame_step >= every)) {
        last_frame_step = viewer.step();
        char name[64];
        std::snprintf(name, sizeof name, "_%07lld.png", static_cast<long long>(viewer.step()));
        const std::string file = png_dir + "/" + (last_run.empty() ? "run" : last_run) + name;
        if (!cv::imwrite(file, viewer.render())) log->error("cannot write {}", file);
        if (max_frames > 0 && ++written >= max_frames) break;
      }
      continue;
    }
    // A window: redrawn about 20 times a second (display only; the run never waits for it).
    if (std::chrono::steady_clock::now() - last_show > std::chrono::milliseconds(50)) {
      cv::imshow("afford-viewer", viewer.render());
      cv::waitKey(1);
      last_show = std::chrono::steady_clock::now();
    }
  }
  log->info("stopped");
  return 0;
}
