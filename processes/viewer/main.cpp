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

#include "afford/channels.hpp"
#include "afford/decision_t.hpp"
#include "afford/effect_t.hpp"
#include "afford/focus_t.hpp"
#include "afford/image.hpp"
#include "afford/logging.hpp"
#include "afford/node.hpp"
#include "afford/prediction_t.hpp"
#include "afford/run_config_t.hpp"
#include "afford/scene_t.hpp"
#include "viewer/viewer.hpp"

namespace {

struct Listener {
  afford::Viewer& viewer;
  spdlog::logger& log;
  std::string run_id;

  template <typename Msg>
  bool decode(const lcm::ReceiveBuffer* b, Msg& m, const char* channel) {
    if (m.decode(b->data, 0, b->data_size) < 0) {
      log.warn("{}: dropped a message that does not decode", channel);
      return false;
    }
    return run_id.empty() || m.run_id == run_id;  // only the run being shown (after RUN_CONFIG)
  }
  void onConfig(const lcm::ReceiveBuffer* b, const std::string&) {
    afford::run_config_t m;
    if (m.decode(b->data, 0, b->data_size) < 0) return log.warn("RUN_CONFIG: dropped a message that does not decode");
    std::string phase = "intrinsic";
    try {
      const YAML::Node cfg = YAML::Load(m.config_yaml);
      if (cfg["phase"]) phase = cfg["phase"].as<std::string>();
    } catch (const YAML::Exception&) {
    }
    run_id = m.run_id;
    viewer.onRun(m.run_id, phase + " " + m.experiment + " " + m.system);
    log.info("showing run '{}'", m.run_id);
  }
  void onScene(const lcm::ReceiveBuffer* b, const std::string&) {
    afford::scene_t m;
    if (!decode(b, m, afford::channel::kScene)) return;
    try {
      viewer.onScene(m.step, afford::decodeScene(m.data, m.width, m.height), m.cause == afford::scene_t::CAUSE_GOAL);
    } catch (const std::exception& e) {
      log.warn("SCENE: {}", e.what());
    }
  }
  void onFocus(const lcm::ReceiveBuffer* b, const std::string&) {
    afford::focus_t m;
    if (!decode(b, m, afford::channel::kFocus)) return;
    viewer.onFocus(m.step, m.image, m.side, m.x, m.y, m.kind == afford::focus_t::GOAL_SCAN);
  }
  void onPrediction(const lcm::ReceiveBuffer* b, const std::string&) {
    afford::prediction_t m;
    if (!decode(b, m, afford::channel::kPrediction) || m.affordance.size() != 4) return;
    viewer.onPrediction(m.step, {m.affordance[0], m.affordance[1], m.affordance[2], m.affordance[3]});
  }
  void onEffect(const lcm::ReceiveBuffer* b, const std::string&) {  // the gaze after the change-driven scan
    afford::effect_t m;
    if (!decode(b, m, afford::channel::kEffect)) return;
    viewer.onFocus(m.step, m.image, m.side, m.after_x, m.after_y, false);
  }
  void onDecision(const lcm::ReceiveBuffer* b, const std::string&) {
    afford::decision_t m;
    if (!decode(b, m, afford::channel::kDecision)) return;
    viewer.onDecision(m.step, m.acted, m.action, m.motivation, m.threshold);
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
  CLI11_PARSE(app, argc, argv);
  auto log = afford::makeLogger("viewer", level);
  afford::installStopHandlers();
  lcm::LCM lcm(url);
  if (!lcm.good()) {
    log->error("cannot open LCM at '{}'", url);
    return 1;
  }
  if (!png_dir.empty()) std::filesystem::create_directories(png_dir);
  afford::Viewer viewer;
  Listener listener{viewer, *log, ""};
  lcm.subscribe(afford::channel::kRunConfig, &Listener::onConfig, &listener);
  lcm.subscribe(afford::channel::kScene, &Listener::onScene, &listener)->setQueueCapacity(1000);
  lcm.subscribe(afford::channel::kFocus, &Listener::onFocus, &listener)->setQueueCapacity(1000);
  lcm.subscribe(afford::channel::kPrediction, &Listener::onPrediction, &listener)->setQueueCapacity(1000);
  lcm.subscribe(afford::channel::kDecision, &Listener::onDecision, &listener)->setQueueCapacity(1000);
  lcm.subscribe(afford::channel::kEffect, &Listener::onEffect, &listener)->setQueueCapacity(1000);
  log->info("watching {}{}", url, png_dir.empty() ? "" : ", frames to " + png_dir);

  std::int64_t written = 0, last_frame_step = -1;
  std::string last_run;
  auto last_show = std::chrono::steady_clock::now();
  while (!afford::stopRequested()) {
    lcm.handleTimeout(20);
    if (!png_dir.empty()) {
      if (listener.run_id != last_run) last_run = listener.run_id, last_frame_step = -1;
      if (viewer.step() >= 0 && (last_frame_step < 0 || viewer.step() >= last_frame_step + every)) {
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
