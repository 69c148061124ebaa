// The page of `afford watch`: an HTTP server (cpp-httplib, from Debian, for
// requests and answers; its connections are ours, connections.hpp) that
// serves one page and streams the WatchState to it as server-sent events. It
// never slows the run: the feed only changes the state and wakes the streams;
// each stream sends the latest snapshot when it can (at most `most_per_second`
// a second), so a slow or paused browser misses snapshots and holds nothing
// but its socket, and one that stops reading is dropped after the write
// timeout.
//
// Exposure is explicit: loopback unless another address is given; then a
// token is required on every request (?token=... or "Authorization: Bearer
// ..."), and a request without it is refused with 401, from its head alone.
// A client that does not finish its request holds no worker.
#pragma once
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <set>
#include <memory>
#include <string>
#include <vector>

#include "experiment/watch/connections.hpp"
#include "experiment/watch/state.hpp"

namespace afford {

// What the page's controls ask of a log's playback; "" or why not.
class PlaybackControls {
 public:
  virtual ~PlaybackControls() = default;
  virtual std::string control(const std::string& command, const std::string& value) = 0;
};

struct WatchServerOptions {
  std::string bind = "127.0.0.1";
  int port = 8077;              // 0: any free port (port() says which)
  std::string token;            // required on every request when not empty
  int most_streams = 16;        // pages following at once; more are refused (503)
  double most_per_second = 5;   // snapshots a stream sends at most
  int timeout_s = 5;            // a request not in whole, an idle connection, an answer not taken: dropped after it
  std::size_t most_connections = 8192;  // waiting for their requests at once; more: the oldest dropped
};

// True for 127.0.0.0/8, ::1 and "localhost".
bool isLoopback(const std::string& address);
// A new random token (32 hex digits, libsodium).
std::string newToken();

class WatchServer {
 public:
  WatchServer(WatchState& state, WatchServerOptions options, PlaybackControls* controls = nullptr);
  ~WatchServer();
  WatchServer(const WatchServer&) = delete;
  WatchServer& operator=(const WatchServer&) = delete;

  // Binds and serves on threads of its own; throws std::runtime_error naming the address and port if it
  // cannot bind (a port in use is never shared).
  void start();
  // Waits until every page following has been sent the state as it is now, or `most` has passed (a page
  // that stopped reading is not waited for past it): the last of a run shown before the server stops.
  void flush(std::chrono::milliseconds most);
  void stop();
  int port() const { return port_; }
  // The page's addresses (with its token when one is required): the address bound; for a wildcard one
  // (0.0.0.0, ::), each address of this machine's interfaces that are up, the others' first, loopback last.
  std::vector<std::string> urls() const;
  int streams() const { return streams_.load(); }
  StageCounts connections() const { return stage_ ? stage_->counts() : StageCounts{}; }

 private:
  class Http;
  void routes();
  bool authorised(const std::string& query_token, const std::string& header) const;
  // A page was sent version `now` (none: it is gone) where it had been sent `was` (none: it is new).
  void sentNow(std::optional<std::uint64_t> was, std::optional<std::uint64_t> now);

  WatchState& state_;
  WatchServerOptions options_;
  PlaybackControls* controls_;
  std::unique_ptr<Http> server_;
  std::unique_ptr<ConnectionStage> stage_;
  int port_ = -1;
  std::atomic<int> streams_{0};
  // The version of the state each following page was sent last (flush waits on it).
  std::mutex sent_mutex_;
  std::condition_variable sent_cv_;
  std::multiset<std::uint64_t> sent_;
  std::atomic<bool> stopping_{false};
};

// The page (experiment/watch/page.html, built in).
const char* watchPage();

}  // namespace afford
