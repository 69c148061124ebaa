// A page following live buses: `afford watch` on a run's bus, and `afford
// experiment --watch` inside the experiment's own process. The page is served
// where serve() is called and the buses are heard where listen() is called:
// the experiment serves its page before it enters its private network
// namespace (the page's socket stays in the namespace it was made in, so the
// page opens from the host) and listens once inside it. One listener per bus
// (a job slot each), each on a thread of its own, at a lower priority: the
// runs go first. Every bus feeds one WatchState, which shows the latest run
// whose RUN_CONFIG any of them said, and lists every run heard.
#pragma once
#include <spdlog/spdlog.h>

#include <atomic>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "afford/auth.hpp"
#include "afford/config.hpp"
#include "experiment/watch/server.hpp"
#include "experiment/watch/state.hpp"

namespace afford {

struct LiveWatchOptions {
  WatchServerOptions server;
  std::string bus_key;  // the key file ("": $AFFORD_BUS_KEY's, or an unkeyed bus)
  int batch_ms = 20;    // the bus's datagrams taken every this many ms, in one go (0: each as it comes)
  int nice = 10;        // how much the watcher's threads lower their priority
  bool say_runs = true; // "showing run ..." said of each run shown (on stderr)
};

class LiveWatch {
 public:
  LiveWatch(const ProtocolConfig& protocol, LiveWatchOptions options);
  ~LiveWatch();
  LiveWatch(const LiveWatch&) = delete;
  LiveWatch& operator=(const LiveWatch&) = delete;

  // Binds the page in the network namespace of the calling thread and serves it; throws std::runtime_error
  // naming the address and port if it cannot.
  void serve();
  // Opens each bus in the network namespace of the calling thread and hears it on a thread of its own;
  // throws std::runtime_error naming the bus if one does not open.
  void listen(const std::vector<std::string>& urls);
  void stop();
  // The page's addresses, the first the one to open (several for a wildcard --bind: each of this machine's).
  std::vector<std::string> pageUrls() const { return server_.urls(); }
  bool keyed() const { return key_ != nullptr; }
  WatchState& state() { return state_; }

 private:
  struct Listener;
  const ProtocolConfig& protocol_;
  LiveWatchOptions options_;
  std::shared_ptr<const BusKey> key_;
  WatchState state_;
  WatchServer server_;
  std::shared_ptr<spdlog::logger> log_;
  std::atomic<bool> stopping_{false};
  std::vector<std::unique_ptr<Listener>> listeners_;
  std::vector<std::thread> threads_;
};

// Lowers the calling thread's priority by `nice` (Linux: each thread has its own), saying so if it cannot.
void lowerThreadPriority(int nice);

}  // namespace afford
