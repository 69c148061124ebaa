// afford watch: a run followed in the browser (experiment/watch/): live from its
// bus as a passive listener, or played from its log with --log.
#include <fcntl.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <memory>
#include <thread>

#include "experiment/run/outcome.hpp"
#include "afford/process_main.hpp"
#include "afford/protocol.hpp"
#include "apps/afford/commands.hpp"
#include "apps/afford/commands/running.hpp"
#include "experiment/watch/live.hpp"
#include "experiment/watch/player.hpp"
#include "experiment/watch/server.hpp"
#include "experiment/watch/state.hpp"

namespace afford {

namespace {

struct WatchArgs {
  std::vector<std::string> urls;
  std::string bus_key, token_file, out, group, log_root = defaultLogRoot();
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
  const auto text = readSmallFile(a.token_file, 4096);  // (a FIFO or a huge file is not read)
  std::istringstream in(text.value_or(""));
  std::string token;
  if (!text || !std::getline(in, token) || token.size() < 16 || token.size() > 256)
    throw std::runtime_error("--token-file " + a.token_file + ": cannot read a token of 16 to 256 characters from it");
  return token;
}

// What to watch: the buses given, else the experiment of --out, the group of --group, or the one experiment or
// group running in the log root.
Watchable watched(const WatchArgs& a) {
  if (!a.urls.empty()) return {"", a.urls, a.bus_key, 0};
  Watchable w;
  if (!a.out.empty()) {
    w = runningExperiment(a.out);
  } else if (!a.group.empty()) {
    w = runningGroup(a.log_root, a.group);
  } else {
    const std::vector<Watchable> found = runningIn(a.log_root);
    if (found.empty())
      throw std::runtime_error("nothing to watch in " + a.log_root + ": no experiment with a run folder there runs now, "
                               "and no scripts/procs.sh group there has a process alive. Give --out DIR (an "
                               "experiment's folder), --group NAME, --log-root DIR or --lcm-url URL; or start the "
                               "experiment with `afford experiment ... --watch`");
    if (found.size() > 1) {
      std::string which;
      for (const Watchable& f : found) which += "\n  " + f.what;
      throw std::runtime_error(std::to_string(found.size()) + " things run in " + a.log_root +
                               ": say which with --out DIR or --group NAME:" + which);
    }
    w = found.front();
  }
  if (!a.bus_key.empty()) w.bus_key = a.bus_key;
  return w;
}

// Into the network namespace of the process `pid` (the calling thread only: the page's threads and socket stay).
void enterNetnsOf(const Watchable& w) {
  if (w.pid <= 0) return;
  const std::string path = "/proc/" + std::to_string(w.pid) + "/ns/net";
  struct stat theirs {}, mine {};
  if (stat(path.c_str(), &theirs) != 0)
    throw std::runtime_error("the " + w.what + " has no process " + std::to_string(w.pid) + " any more: it ended");
  if (stat("/proc/thread-self/ns/net", &mine) == 0 && mine.st_ino == theirs.st_ino && mine.st_dev == theirs.st_dev) return;
  const int fd = open(path.c_str(), O_RDONLY | O_CLOEXEC);
  const bool entered = fd >= 0 && setns(fd, CLONE_NEWNET) == 0;
  const int why = errno;
  if (fd >= 0) close(fd);
  if (!entered)
    throw std::runtime_error("cannot enter the network namespace of the " + w.what + " (process " +
                             std::to_string(w.pid) + "): " + std::strerror(why) +
                             ". Run afford watch as root, or start the experiment with `afford experiment ... --watch`");
}

void printPage(const std::vector<std::string>& urls) {
  std::printf("the page: %s\n", urls.front().c_str());
  for (std::size_t k = 1; k < urls.size(); ++k) std::printf("      or: %s\n", urls[k].c_str());
}

int watchLive(WatchArgs& a, const FrontDoor& door) {
  giveWay(a.nice);
  const ProtocolConfig protocol = loadProtocol(door.config_dir);
  const Watchable w = watched(a);
  LiveWatchOptions o;
  o.server = a.server, o.bus_key = w.bus_key, o.batch_ms = a.batch_ms, o.nice = a.nice;
  LiveWatch watch(protocol, o);
  watch.serve();  // here: the page opens from where afford watch was started
  enterNetnsOf(w);
  watch.listen(w.urls);
  std::string buses;
  for (const std::string& u : w.urls) buses += (buses.empty() ? "" : ", ") + u;
  std::printf("watching %s%s%s\n", w.what.empty() ? "" : (w.what + ": ").c_str(), buses.c_str(),
              watch.keyed() ? " (keyed)" : "");
  printPage(watch.pageUrls());
  std::fflush(stdout);
  installStopHandlers();
  while (!stopRequested()) std::this_thread::sleep_for(std::chrono::milliseconds(100));  // signals set a flag only
  watch.stop();
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
              static_cast<long long>(player.lastStep()), server.urls().front().c_str());
  for (std::size_t k = 1; k < server.urls().size(); ++k) std::printf("      or: %s\n", server.urls()[k].c_str());
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
  watch->add_option("--lcm-url", a->urls, "the runs' bus (repeatable: several buses); without it, the experiment of "
                                          "--out, the group of --group, or the one running in the log root");
  watch->add_option("--out", a->out, "watch the experiment running in this folder (its --out)");
  watch->add_option("--group", a->group, "watch the scripts/procs.sh group of this name");
  watch->add_option("--log-root", a->log_root, "where --group and a running experiment are looked for (default: "
                                               "$AFFORD_LOGS, else logs)");
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
            if (!a->urls.empty() + !a->out.empty() + !a->group.empty() > 1)
              throw ConfigError("give one of --lcm-url, --out and --group: each says which runs to watch");
            if (!a->player.log.empty() && (!a->urls.empty() || !a->out.empty() || !a->group.empty()))
              throw ConfigError("--log plays a recorded run: --lcm-url, --out and --group watch live ones");
            a->server.token = tokenFor(*a);
            moreFiles();
            return a->player.log.empty() ? watchLive(*a, door) : watchLog(*a, door);
          }};
}

}  // namespace afford
