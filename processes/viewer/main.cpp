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
#include "afford/logging.hpp"
#include "afford/version.hpp"
#include "afford/bus.hpp"
#include "afford/edge.hpp"
#include "afford/node.hpp"
#include "afford/process_main.hpp"
#include "viewer/feed.hpp"
#include "viewer/viewer.hpp"

int main(int argc, char** argv) {
  CLI::App app{"afford viewer: watch a run (scene, gaze, goal, focus, affordances, motivation)", "afford-viewer"};
  app.set_version_flag("--version", std::string("afford-viewer ") + afford::affordVersion());
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
  afford::ViewFeed feed(viewer, protocol, "", log.get());  // what the viewer hears, through the edge: decoded, checked
  feed.subscribe(edge);
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
