// afford watch: a run followed in the browser (experiment/watch/): live from its
// bus as a passive listener, or played from its log with --log.
#include <lcm/lcm-cpp.hpp>
#include <sys/resource.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <thread>

#include "afford/auth.hpp"
#include "afford/bus.hpp"
#include "afford/edge.hpp"
#include "afford/logging.hpp"
#include "afford/process_main.hpp"
#include "afford/protocol.hpp"
#include "apps/afford/commands.hpp"
#include "experiment/watch/player.hpp"
#include "experiment/watch/sampler.hpp"
#include "experiment/watch/server.hpp"
#include "experiment/watch/state.hpp"
#include "viewer/feed.hpp"

namespace afford {

namespace {

struct WatchArgs {
  std::string url = "udpm://239.255.76.67:7667?ttl=0", bus_key, token_file;
  WatchServerOptions server;
  PlayerOptions player;
  bool paused = false;
  int nice = 10;
  int batch_ms = 20;
};

// The watcher gives way to the run: its threads (made after this) take the CPU a run leaves.
void giveWay(int nice) {
  if (nice > 0 && setpriority(PRIO_PROCESS, 0, nice) != 0)
    std::fprintf(stderr, "afford watch: cannot lower its priority (--nice %d): %s\n", nice, std::strerror(errno));
}

// Every file the process may have: each connection to the page is one, and held ones are many (the page's
// server bounds them below this; connections.hpp).
void moreFiles() {
  rlimit files{};
  if (getrlimit(RLIMIT_NOFILE, &files) == 0 && files.rlim_cur < files.rlim_max) {
    files.rlim_cur = files.rlim_max;
    setrlimit(RLIMIT_NOFILE, &files);
  }
}

std::string tokenFor(const WatchArgs& a) {
  if (a.token_file.empty()) return isLoopback(a.server.bind) ? "" : newToken();
  std::ifstream in(a.token_file);
  std::string token;
  if (!in || !std::getline(in, token) || token.size() < 16 || token.size() > 256)
    throw std::runtime_error("--token-file " + a.token_file + ": cannot read a token of 16 to 256 characters from it");
  return token;
}

int watchLive(WatchArgs& a, const FrontDoor& door) {
  giveWay(a.nice);
  const ProtocolConfig protocol = loadProtocol(door.config_dir);
  const std::shared_ptr<const BusKey> key = busKeyFrom(a.bus_key);
  // The bus's datagrams taken every batch_ms, not one at a time: a watcher woken for each would take the
  // run's CPU (third_party/lcm patch 0011); what a page is sent (5 states a second) does not change.
  const std::string url = a.batch_ms > 0 ? withBusOption(a.url, "receive_batch_ms", a.batch_ms) : a.url;
  std::unique_ptr<lcm::LCM> bus = openBus(url, protocol.bus);
  WatchState state;
  auto log = makeLogger("watch", "info");
  Edge edge(*bus, log, "watch", protocol);
  edge.useKey(key);
  ViewFeed feed(state, protocol, "", log.get());
  feed.subscribe(edge, false);
  WatchServer server(state, a.server);
  server.start();
  std::printf("watching %s%s\nthe page: %s\n", a.url.c_str(), key ? " (keyed)" : "", server.url().c_str());
  std::fflush(stdout);
  installStopHandlers();
  const auto gap = std::chrono::duration_cast<StepSampler::Clock::duration>(
      std::chrono::duration<double>(1.0 / a.server.most_per_second));
  StepSampler sampler(
      state,
      [&edge](bool on) {
        edge.take(ch::focus.name, on);
        edge.take(ch::prediction.name, on);
      },
      gap);
  while (!stopRequested()) {
    pumpBus(*bus, 50);
    sampler.tick(StepSampler::Clock::now());
  }
  server.stop();
  return 0;
}

int watchLog(WatchArgs& a, const FrontDoor& door) {
  giveWay(a.nice);
  const ProtocolConfig protocol = loadProtocol(door.config_dir);
  WatchState state;
  a.player.bus_key = a.bus_key;
  a.player.play = !a.paused;
  LogPlayer player(state, protocol, a.player, *door.log);
  WatchServer server(state, a.server, &player);
  server.start();
  std::printf("playing %s: run %s, steps %lld to %lld\nthe page: %s\n", a.player.log.string().c_str(),
              player.runId().c_str(), static_cast<long long>(player.firstStep()),
              static_cast<long long>(player.lastStep()), server.url().c_str());
  std::fflush(stdout);
  installStopHandlers();
  std::thread stopper([&] {
    while (!stopRequested()) std::this_thread::sleep_for(std::chrono::milliseconds(100));  // signals set a flag only
    player.stop();
  });
  player.run();
  stopper.join();
  server.stop();
  return 0;
}

}  // namespace

Command watchCommand(CLI::App& app, const FrontDoor& door) {
  auto a = std::make_shared<WatchArgs>();
  auto* watch = app.add_subcommand("watch", "follow a run in the browser: live on its bus (a passive listener), or "
                                            "played from its log with --log");
  watch->add_option("--lcm-url", a->url, "the run's bus")->capture_default_str();
  watch->add_option("--bus-key", a->bus_key, "key file of a keyed bus (default: the file $AFFORD_BUS_KEY names)");
  watch->add_option("--log", a->player.log, "play this run log (a log folder or one .lcm file) instead of a live bus");
  watch->add_option("--run", a->player.run_id, "with --log: the run to play, in a log that holds several");
  watch->add_option("--speed", a->player.speed, "with --log: steps a second")->capture_default_str();
  watch->add_flag("--paused", a->paused, "with --log: start paused at the first step");
  watch->add_option("--bind", a->server.bind, "the address to serve the page on; anything but loopback requires a "
                                              "token")->capture_default_str();
  watch->add_option("--port", a->server.port, "the port (0: any free one)")->capture_default_str()->check(CLI::Range(0, 65535));
  watch->add_option("--token-file", a->token_file, "read the token from this file (default: a new one, printed, "
                                                   "when --bind is not loopback)");
  watch->add_option("--nice", a->nice, "lower its own priority by this much (0..19), so that on a busy machine the "
                                       "run goes first and the page lags instead")->capture_default_str()->check(CLI::Range(0, 19));
  watch->add_option("--batch-ms", a->batch_ms, "take the bus's messages every this many milliseconds, in one go, "
                                               "rather than each as it comes (0: each as it comes)")
      ->capture_default_str()->check(CLI::Range(0, 1000));
  watch->add_option("--updates", a->server.most_per_second, "states a page is sent a second, at most")
      ->capture_default_str()->check(CLI::Range(0.5, 30.0));
  watch->add_option("--most-pages", a->server.most_streams, "pages following at once; more are refused")
      ->capture_default_str()->check(CLI::Range(1, 256));
  return {watch, [a, &door] {
            a->server.token = tokenFor(*a);
            moreFiles();
            return a->player.log.empty() ? watchLive(*a, door) : watchLog(*a, door);
          }};
}

}  // namespace afford
