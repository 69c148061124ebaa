// The connections of the page's server (experiment/watch/server.hpp): one
// thread (epoll) accepts them and reads each until its whole request is in;
// only then does a worker take it, and a worker never waits for a client's
// bytes. What needs no worker is answered here: a head the server's check
// refuses (off loopback: no token, 401), a head over its bound (431), a body
// over its bound (413) or of no stated length (400). A connection between
// requests, and the rest of a response its client is slow to take, wait here
// too. Every wait has a deadline, and what waits at once is bounded: when
// full, the oldest waiting connection is dropped for the new one.
#pragma once
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

namespace httplib {
struct Request;
class Stream;
class ThreadPool;
}  // namespace httplib

namespace afford {

struct StageOptions {
  int timeout_s = 5;                      // for a request to come in whole, an idle connection, a response to be taken
  int workers = 20;                       // threads serving complete requests
  std::size_t most_connections = 8192;    // waiting here at once (fewer if the process's file limit is lower)
  std::size_t most_bytes = 32u << 20;     // of requests and responses waiting here, together
  std::size_t head_bytes = 64 * 1024;     // a request's head, at most (431)
  std::size_t body_bytes = 64 * 1024;     // a request's body, at most (413)
  int requests_per_connection = 5;        // then the connection is closed
  std::string streamed_path;              // its answer (an event stream) is written by its worker as it goes
};

// What the server says of a request head: served (status 0), or refused with this status and why.
struct Verdict {
  int status = 0;
  std::string why;
};

struct StageHooks {
  std::function<Verdict(const httplib::Request&)> check;  // the head alone, before any worker
  // A worker's: serve the one request on the stream; false, or `closed`, ends the connection.
  std::function<bool(httplib::Stream&, bool close_connection, bool& closed)> serve;
  std::function<std::string(int status)> why;  // the words of the stage's own refusals
};

struct StageCounts {
  std::uint64_t held = 0;     // connections waiting here now
  std::uint64_t dropped = 0;  // dropped to make room (connections or bytes) or at their deadline
  std::uint64_t refused = 0;  // answered here with a refusal
  std::uint64_t paused = 0;   // times accepting paused: no file left to take a connection with
  std::uint64_t wakeups = 0;  // of the stage's thread
};

// A listening socket on host:port (port 0: any; `bound` says which). Never shared: a second server on a
// port in use fails. Throws std::runtime_error naming the address and why.
int listenOn(const std::string& host, int port, int& bound);

class ConnectionStage {
 public:
  // Takes the listening socket (closed on stop).
  ConnectionStage(int listener, StageOptions options, StageHooks hooks);
  ~ConnectionStage();
  ConnectionStage(const ConnectionStage&) = delete;
  ConnectionStage& operator=(const ConnectionStage&) = delete;

  void start();
  void stop();
  StageCounts counts() const;

 private:
  struct Conn;
  using Clock = std::chrono::steady_clock;
  enum class Queue { Reading, Flushing, Closing };

  void loop();
  void acceptAll();
  void onReadable(Conn& c);
  void onWritable(Conn& c);
  void onDraining(Conn& c);
  void scan(Conn& c);
  void examineHead(Conn& c);
  void refuse(Conn& c, int status, const std::string& why);
  void dispatch(Conn& c);
  void work(Conn* c);
  void comeBack(Conn* c);
  void takeReturned();
  void enter(Conn& c, Queue q);
  void finish(Conn& c);
  void drop(Conn& c);
  void close(Conn& c);
  bool makeRoom();
  void shed();
  void expire(Clock::time_point now);
  int waitMs(Clock::time_point now) const;
  void pauseAccepting(Clock::time_point now);
  void resumeAccepting();
  void account(std::int64_t bytes);

  int listener_, epoll_ = -1, wake_ = -1;
  StageOptions options_;
  StageHooks hooks_;
  std::size_t most_connections_;
  std::unique_ptr<httplib::ThreadPool> pool_;
  std::thread thread_;
  std::atomic<bool> stopping_{false};
  bool running_ = false;
  // The stage thread's own:
  std::unordered_map<int, std::unique_ptr<Conn>> conns_;
  std::list<Conn*> queues_[3];  // each in the order of its deadlines (entered, plus one wait for all)
  std::size_t bytes_ = 0;
  bool accept_paused_ = false;
  Clock::time_point resume_at_{};
  // Handed back by the workers:
  std::mutex returned_mutex_;
  std::vector<Conn*> returned_;
  bool closed_ = false;
  // For counts():
  std::atomic<std::uint64_t> held_{0}, dropped_{0}, refused_{0}, paused_{0}, wakeups_{0};
};

}  // namespace afford
