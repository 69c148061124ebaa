// afford watch's state and page server (experiment/watch/): bounded whatever
// the run's length, a page that stops reading holds nothing, off loopback a
// token is required, bad requests are refused without holding memory, and
// clients that do not finish their requests (or take their answers) hold no
// worker.
#include <gtest/gtest.h>
#include <httplib.h>
#include <netinet/in.h>
#include <nlohmann/json.hpp>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <fstream>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "afford/image.hpp"
#include "experiment/watch/sampler.hpp"
#include "experiment/watch/server.hpp"
#include "experiment/watch/state.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

long statusKb(const char* field) {  // VmRSS or VmHWM of this process
  std::ifstream in("/proc/self/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind(field, 0) == 0) return std::stol(line.substr(line.find(':') + 1));
  return -1;
}

// A run fed to a view: `steps` steps, each with a scene of its own, a focus, a decision, and a table every 10.
void feedRun(RunView& v, const std::string& run, std::int64_t steps, const RunConfig& c) {
  run_config_t m;
  m.run_id = run, m.experiment = "base", m.system = "IMP";
  v.onRun(run, "intrinsic base IMP");
  v.onConfig(m, c);
  cv::Mat scene = blankScene(150);
  for (std::int64_t t = 0; t < steps; ++t) {
    scene.at<cv::Vec3b>(static_cast<int>(t % 150), static_cast<int>(t / 150 % 150)) = cv::Vec3b(255, t % 256, 7);
    v.onScene(t, scene, false);
    v.onFocus(t, cropFocus(scene, {30, 30}, 21), 21, 0.2, 0.2, false);
    v.onPrediction(t, {0.9, 0.1, 0.5, 0.7});
    v.onDecision(t, t % 3 == 0, 1, 0.01 * static_cast<double>(t % 50), 0.2);
    if (t % 10 == 0) {
      affordance_table_t table;
      table.run_id = run, table.step = t, table.n_objects = static_cast<int>(c.world.objects.size()), table.n_actions = 4;
      table.affordance.assign(c.world.objects.size(), std::vector<double>{0.5, 0.4, 0.3, static_cast<double>(t) / steps});
      v.onTable(table);
    }
  }
}

TEST(WatchState, HoldsWhatARunOfAnyLengthShowsWithinItsBounds) {
  const RunConfig c = test::shippedConfig();
  WatchLimits limits;
  WatchState state(limits);
  for (int r = 0; r < 100; ++r) feedRun(state, "other-" + std::to_string(r), 1, c);
  feedRun(state, "long", 20000, c);
  const json s = json::parse(state.snapshot(true));
  EXPECT_EQ(s["step"], 19999);
  EXPECT_EQ(s["scene"]["step"], 19999);
  EXPECT_EQ(s["motivation"].size(), limits.trace_length);
  const auto& steps = s["curves"]["steps"];
  EXPECT_LE(steps.size(), limits.curve_points + 1);  // (and the latest table at the end)
  EXPECT_GE(steps.size(), limits.curve_points / 2);
  EXPECT_EQ(steps.front(), 0);
  EXPECT_EQ(steps.back(), 19990);  // the curves reach the last table
  EXPECT_EQ(s["curves"]["objects"].size(), c.world.objects.size());
  EXPECT_EQ(s["runs"].size(), limits.most_runs);
  EXPECT_EQ(s["runs"][0]["id"], "long");  // the latest first
}

// FOCUS and PREDICTION, said every step, are taken one step at a time, once per gap; let go in between; the
// page's picture is that step's. In another phase than the intrinsic one (whose FOCUS carries a goal's
// scan) they are taken throughout.
TEST(WatchSampler, TakesAStepOfFocusAndPredictionOncePerGapAndShowsThatStep) {
  RunConfig c = test::shippedConfig();
  WatchState state;
  bool taking = true;
  int turns = 0;
  const auto gap = std::chrono::milliseconds(200);
  StepSampler sampler(state, [&](bool on) { taking = on, ++turns; }, gap);
  run_config_t m;
  m.run_id = "r";
  state.onRun("r", "intrinsic base IMP");
  state.onConfig(m, c);
  const cv::Mat scene = blankScene(150);
  // One step of the run, with or without the sampled channels (what the bus hands on while they are let go):
  // a scene, the focus on it and its prediction, the decision (to act on every other step).
  auto step = [&](std::int64_t t) {
    state.onScene(t, scene, false);
    if (taking) {
      state.onFocus(t, cropFocus(scene, {30, 30}, 21), 21, 0.2, 0.2, false);
      state.onPrediction(t, {0.9, 0.1, 0.5, 0.7});
    }
    state.onDecision(t, t % 2 == 0, 1, 0.1, 0.2);
  };
  const auto t0 = Clock::now();
  sampler.tick(t0);
  EXPECT_TRUE(taking) << "nothing taken yet";
  step(0);
  sampler.tick(t0);
  EXPECT_FALSE(taking) << "a step's focus and prediction are in";
  for (std::int64_t t = 1; t < 50; ++t) step(t), sampler.tick(t0 + gap / 2);
  EXPECT_FALSE(taking) << "taken again before the gap";
  sampler.tick(t0 + gap);
  EXPECT_TRUE(taking);
  step(50);
  sampler.tick(t0 + gap);
  EXPECT_FALSE(taking);
  step(51);
  const json s = json::parse(state.snapshot(false));
  EXPECT_EQ(s["step"], 51) << "the run's step: the latest";
  // The picture is of one step, the latest sampled: its scene, its focus, its decision.
  EXPECT_EQ(s["focus"]["step"], 50);
  EXPECT_EQ(s["scene"]["step"], 50);
  EXPECT_EQ(s["decision"], "act: " + std::string(kActionNames[1]));
  EXPECT_EQ(s["motivation"].size(), 52u) << "the trace: every step";
  EXPECT_EQ(turns, 3);  // let go, taken, let go
  // The extrinsic phase: taken throughout.
  c.phase = Phase::Extrinsic;
  state.onRun("x", "extrinsic base IMP");
  state.onConfig(m, c);
  sampler.tick(t0 + gap);
  EXPECT_TRUE(taking);
  for (std::int64_t t = 0; t < 5; ++t) step(t), sampler.tick(t0 + gap * (t + 2));
  EXPECT_TRUE(taking);
}

// The server's address on loopback.
sockaddr_in loopback(int port) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  return a;
}

// A raw client socket on the server's port.
int connectTo(int port) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a = loopback(port);
  if (connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    close(fd);
    return -1;
  }
  return fd;
}

void sendAll(int fd, const std::string& data) {
  std::size_t at = 0;
  while (at < data.size()) {
    const ssize_t n = send(fd, data.data() + at, data.size() - at, MSG_NOSIGNAL);
    if (n <= 0) return;  // the server closed it: refused
    at += static_cast<std::size_t>(n);
  }
}

// What the server answered, up to `bytes`, or "" if it closed the connection first.
std::string answer(int fd, std::size_t bytes = 64) {
  timeval tv{10, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  std::string out(bytes, '\0');
  const ssize_t n = recv(fd, out.data(), out.size(), 0);
  out.resize(n > 0 ? static_cast<std::size_t>(n) : 0);
  return out;
}

template <class F>
bool eventually(F cond, int seconds = 20) {
  const auto deadline = Clock::now() + std::chrono::seconds(seconds);
  while (Clock::now() < deadline) {
    if (cond()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return cond();
}

TEST(WatchServer, APageThatStopsReadingHoldsNothingAndOthersFollowOn) {
  const RunConfig c = test::shippedConfig();
  WatchState state;
  WatchServerOptions o;
  o.port = 0, o.timeout_s = 1, o.most_per_second = 50;  // (its buffers fill sooner)
  WatchServer server(state, o);
  server.start();
  // A page that asks for the stream and never reads it, its buffer small.
  const int stuck = connectTo(server.port());
  ASSERT_GE(stuck, 0);
  int small = 4096;
  setsockopt(stuck, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
  sendAll(stuck, "GET /events HTTP/1.1\r\nHost: x\r\n\r\n");
  ASSERT_TRUE(eventually([&] { return server.streams() == 1; }));
  const long before = statusKb("VmHWM:");
  feedRun(state, "long", 20000, c);  // the feed takes the state's lock only: nothing waits for a page
  // Fed on while the stuck page's stream fails to write and is dropped.
  for (std::int64_t t = 20000; !eventually([&] { return server.streams() == 0; }, 0); ++t) {
    std::vector<std::uint8_t> focus(21 * 21 * 3, static_cast<std::uint8_t>(t));
    state.onFocus(t, focus, 21, 0.5, 0.5, false);
    affordance_table_t table;  // new curves: every snapshot sent has them (a hundred kB)
    table.run_id = "long", table.step = t * 10, table.n_objects = static_cast<int>(c.world.objects.size());
    table.n_actions = 4;
    table.affordance.assign(c.world.objects.size(), std::vector<double>{0.1 * (t % 7), 0.4, 0.3, 0.2});
    state.onTable(table);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    ASSERT_LT(t, 20000 + 4000) << "the stuck page's stream is still open";
  }
  const long grown = statusKb("VmHWM:") - before;
  EXPECT_LT(grown, 32 * 1024) << "kB held while a page did not read";
  // Another page follows the run as it goes on.
  httplib::Client client("127.0.0.1", server.port());
  const auto res = client.Get("/state");
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 200);
  EXPECT_GE(json::parse(res->body)["step"].get<std::int64_t>(), 20000);
  close(stuck);
  server.stop();
}

TEST(WatchServer, OffLoopbackEveryRequestWithoutTheTokenIsRefused) {
  WatchState state;
  WatchServerOptions o;
  o.bind = "0.0.0.0", o.port = 0;
  EXPECT_THROW(WatchServer(state, o), std::runtime_error);  // no token: not served at all
  o.token = newToken();
  EXPECT_EQ(o.token.size(), 32u);
  WatchServer server(state, o);
  server.start();
  EXPECT_NE(server.urls().front().find("?token=" + o.token), std::string::npos);
  httplib::Client client("127.0.0.1", server.port());
  for (const std::string path : {"/", "/state", "/events", "/control?command=play"}) {
    auto res = client.Get(path.c_str());
    ASSERT_TRUE(res) << path;
    EXPECT_EQ(res->status, 401) << path << " without the token";
    const std::string other(o.token.size(), 'f');
    res = client.Get((path + (path.find('?') == std::string::npos ? "?" : "&") + "token=" + other).c_str());
    ASSERT_TRUE(res);
    EXPECT_EQ(res->status, 401) << path << " with another token";
    res = client.Get(path.c_str(), httplib::Headers{{"Authorization", "Bearer " + other}});
    ASSERT_TRUE(res);
    EXPECT_EQ(res->status, 401) << path << " with another bearer token";
  }
  auto res = client.Get(("/state?token=" + o.token).c_str());
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 200);
  res = client.Get("/", httplib::Headers{{"Authorization", "Bearer " + o.token}});
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 200);
  EXPECT_NE(res->body.find("<title>afford watch</title>"), std::string::npos);
  server.stop();
}

TEST(WatchServer, BadRequestsAreRefusedAndHoldNoMemory) {
  rlimit files{};
  getrlimit(RLIMIT_NOFILE, &files);
  files.rlim_cur = std::min<rlim_t>(files.rlim_max, 4096);
  setrlimit(RLIMIT_NOFILE, &files);
  WatchState state;
  WatchServerOptions o;
  o.port = 0, o.timeout_s = 1;
  WatchServer server(state, o);
  server.start();
  const long before = statusKb("VmHWM:");

  // Ten megabytes of header, sent as it is made: short fields, then one long field; four requests of each at once.
  std::string fields;
  for (int i = 0; fields.size() < 65536; ++i) fields += "X-" + std::to_string(i) + ": y\r\n";
  const std::string line(65536, 'a');
  for (const std::string* chunk : std::vector<const std::string*>{&fields, &line}) {
    std::vector<std::thread> senders;
    std::vector<std::string> answers(4);
    for (int k = 0; k < 4; ++k)
      senders.emplace_back([&, k] {
        const int fd = connectTo(server.port());
        sendAll(fd, chunk == &line ? "GET /state HTTP/1.1\r\nX-Long: " : "GET /state HTTP/1.1\r\n");
        for (std::size_t sent = 0; sent < 10'000'000; sent += chunk->size()) sendAll(fd, *chunk);
        sendAll(fd, "\r\n\r\n");
        answers[k] = answer(fd);
        close(fd);
      });
    for (auto& t : senders) t.join();
    // (refused at 64 KB of head, 431, as it arrives)
    for (const auto& a : answers) EXPECT_TRUE(a.empty() || a.rfind("HTTP/1.1 431", 0) == 0) << a;
  }

  // A request that never ends is dropped at its deadline.
  int fd = connectTo(server.port());
  sendAll(fd, "GET /state HTTP/1.1\r\nX-Slow: ");
  const std::string slow = answer(fd);
  EXPECT_TRUE(slow.empty() || slow.rfind("HTTP/1.1 400", 0) == 0) << slow;
  close(fd);

  // A request whose client then closes its side is still answered.
  fd = connectTo(server.port());
  sendAll(fd, "GET /state HTTP/1.1\r\n\r\n");
  shutdown(fd, SHUT_WR);
  EXPECT_EQ(answer(fd).rfind("HTTP/1.1 200", 0), 0u);
  close(fd);

  // A WebSocket upgrade (the page has none), then frames that are not WebSocket's.
  fd = connectTo(server.port());
  sendAll(fd, "GET /events HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
              "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n");
  sendAll(fd, std::string("\x81\xff\x7f\xff\xff\xff\xff\xff\xff\xff\x00\x00\x00\x00garbage", 22));
  const std::string ws = answer(fd, 4096);
  EXPECT_EQ(ws.find("101 Switching"), std::string::npos) << ws;
  close(fd);

  // A thousand sockets opened at once, then closed.
  std::vector<int> many;
  for (int i = 0; i < 1000; ++i) {
    const int s = connectTo(server.port());
    if (s >= 0) many.push_back(s);
  }
  EXPECT_EQ(many.size(), 1000u);
  for (int s : many) close(s);

  // Still serving, and nothing of it held.
  httplib::Client client("127.0.0.1", server.port());
  client.set_read_timeout(30, 0);
  const auto res = client.Get("/state");
  ASSERT_TRUE(res) << httplib::to_string(res.error());
  EXPECT_EQ(res->status, 200);
  // What the server's library refuses is said why, as the server's own refusals are.
  const auto nowhere = client.Get("/nowhere");
  ASSERT_TRUE(nowhere);
  EXPECT_EQ(nowhere->status, 404);
  EXPECT_NE(nowhere->body.find("no such page"), std::string::npos) << nowhere->body;
  fd = connectTo(server.port());
  sendAll(fd, "POST /control?command=play HTTP/1.1\r\nHost: x\r\n\r\n");  // no Content-Length
  const std::string bodiless = answer(fd, 4096);
  close(fd);
  EXPECT_EQ(bodiless.rfind("HTTP/1.1 400", 0), 0u) << bodiless;
  EXPECT_NE(bodiless.find("Content-Length"), std::string::npos) << bodiless;
  const long grown = statusKb("VmHWM:") - before;
  EXPECT_LT(grown, 48 * 1024) << "kB held by bad requests";
  server.stop();
}

// Open: the server has neither closed it nor answered anything on it.
bool open(int fd) {
  char b;
  return recv(fd, &b, 1, MSG_PEEK | MSG_DONTWAIT) < 0 && errno == EAGAIN;
}

// Connections that do not finish their requests, held until the end: idle (nothing sent), stalled (a request
// line and a field, no end), dribbling (a head, a byte every 20 ms, never ending), kept (answered once,
// kept alive, then idle), unread (the event stream asked for, never read).
struct Unfinished {
  std::vector<int> all, waiting, dribbling;  // waiting: all but the streams
  std::atomic<bool> stop{false};
  std::thread dribbler;

  Unfinished(int port, int idle, int stalled, int dribble, int kept, int unread, const std::string& query = "") {
    auto add = [&](const std::string& sent, int buffer = 0) {
      const int fd = connectTo(port);
      EXPECT_GE(fd, 0);
      if (buffer) setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &buffer, sizeof buffer);
      if (!sent.empty()) sendAll(fd, sent);
      all.push_back(fd);
      if (!buffer) waiting.push_back(fd);
      return fd;
    };
    for (int i = 0; i < idle; ++i) add("");
    for (int i = 0; i < stalled; ++i) add("GET /state" + query + " HTTP/1.1\r\nHost: x\r\n");
    for (int i = 0; i < dribble; ++i) dribbling.push_back(add("GET /" + query + " HTTP/1.1\r\nX-Slow: "));
    for (int i = 0; i < kept; ++i) {
      const int fd = add("GET /nowhere" + query + " HTTP/1.1\r\nHost: x\r\n\r\n");
      const std::string a = answer(fd, 4096);  // (the whole answer: a 404 of a few lines)
      EXPECT_EQ(a.rfind("HTTP/1.1 404", 0), 0u) << a;
    }
    for (int i = 0; i < unread; ++i) add("GET /events" + query + " HTTP/1.1\r\nHost: x\r\n\r\n", 4096);
    dribbler = std::thread([this] {
      while (!stop) {
        for (int fd : dribbling) send(fd, "a", 1, MSG_NOSIGNAL);
        std::this_thread::sleep_for(std::chrono::milliseconds(20));  // (the client's pace, not a wait)
      }
    });
  }
  ~Unfinished() {
    stop = true;
    dribbler.join();
    for (int fd : all) close(fd);
  }
  int stillWaiting() const {
    int n = 0;
    for (int fd : waiting) n += open(fd);
    return n;
  }
};

// More connections that never finish a request than the server has workers (20), and the streams of pages
// that never read: the page is served meanwhile, and none of them has been dropped by then.
TEST(WatchServer, ClientsThatDoNotFinishTheirRequestsHoldNoWorker) {
  WatchState state;
  WatchServerOptions o;
  o.port = 0, o.timeout_s = 30;  // (none dropped at its deadline while the test runs)
  WatchServer server(state, o);
  server.start();
  Unfinished held(server.port(), 64, 8, 8, 8, 4);
  ASSERT_TRUE(eventually([&] { return server.streams() == 4; }));
  ASSERT_TRUE(eventually([&] { return server.connections().held >= 64 + 8 + 8 + 8; }));
  httplib::Client client("127.0.0.1", server.port());
  client.set_read_timeout(60, 0);  // (past the server's timeout: an answer only once they are dropped is late)
  for (const char* path : {"/", "/state"}) {
    const auto res = client.Get(path);
    ASSERT_TRUE(res) << path << ": " << httplib::to_string(res.error());
    EXPECT_EQ(res->status, 200) << path;
  }
  EXPECT_EQ(held.stillWaiting(), static_cast<int>(held.waiting.size())) << "answered once the unfinished were dropped";
  EXPECT_EQ(server.streams(), 4);
  server.stop();
}

// The server's end of a client's connection (the test's process is the server's): found by its peer's port.
int serverEnd(int client) {
  sockaddr_in mine{}, peer{};
  socklen_t len = sizeof mine;
  getsockname(client, reinterpret_cast<sockaddr*>(&mine), &len);
  for (int fd = 0; fd < 4096; ++fd) {
    len = sizeof peer;
    if (fd != client && getpeername(fd, reinterpret_cast<sockaddr*>(&peer), &len) == 0 && peer.sin_port == mine.sin_port)
      return fd;
  }
  return -1;
}

// Answers their clients are slow to take (the kernel's buffers of both ends full) wait with the connections,
// not in the workers: more of them than workers, and the page is served; each is then taken whole.
TEST(WatchServer, AnswersTakenSlowlyHoldNoWorker) {
  WatchState state;
  feedRun(state, "long", 20000, test::shippedConfig());  // /state: about 80 kB
  WatchServerOptions o;
  o.port = 0, o.timeout_s = 30, o.most_streams = 2;  // 6 workers
  WatchServer server(state, o);
  server.start();
  std::vector<int> slow;
  for (int i = 0; i < 12; ++i) {
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    int small = 4096;
    setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
    sockaddr_in a = loopback(server.port());
    ASSERT_EQ(connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    int end = -1;  // (once accepted; its send buffer as small as the kernel allows: the answer cannot fit)
    ASSERT_TRUE(eventually([&] { return (end = serverEnd(fd)) >= 0; }));
    ASSERT_EQ(setsockopt(end, SOL_SOCKET, SO_SNDBUF, &small, sizeof small), 0);
    sendAll(fd, "GET /state HTTP/1.1\r\n\r\n");
    slow.push_back(fd);
  }
  httplib::Client client("127.0.0.1", server.port());
  client.set_read_timeout(60, 0);
  const auto res = client.Get("/");
  ASSERT_TRUE(res) << httplib::to_string(res.error());
  EXPECT_EQ(res->status, 200);
  for (int fd : slow) {
    std::string got;
    for (std::string part; !(part = answer(fd, 65536)).empty();) {
      got += part;
      const auto body = got.find("\r\n\r\n");
      const auto length = got.find("Content-Length: ");
      if (body != std::string::npos && length != std::string::npos &&
          got.size() - body - 4 == std::stoul(got.substr(length + 16)))
        break;
    }
    EXPECT_EQ(got.rfind("HTTP/1.1 200", 0), 0u);
    EXPECT_GT(got.size(), 65536u);
    EXPECT_EQ(json::parse(got.substr(got.find("\r\n\r\n") + 4))["step"], 19999) << "the whole answer";
    close(fd);
  }
  server.stop();
}

// Blocks every worker in POST /control until released.
struct BlockingControls : PlaybackControls {
  std::mutex mutex;
  std::condition_variable changed;
  bool released = false;
  int waiting = 0;
  std::string control(const std::string&, const std::string&) override {
    std::unique_lock<std::mutex> lock(mutex);
    ++waiting;
    changed.notify_all();
    changed.wait(lock, [&] { return released; });
    return "";
  }
  void release() {
    std::lock_guard<std::mutex> lock(mutex);
    released = true;
    changed.notify_all();
  }
};

// Off loopback, with every worker busy and idle connections held, a request without the token is still
// refused: from its head, never waiting for a worker.
TEST(WatchServer, OffLoopbackARequestWithoutTheTokenIsRefusedWithoutAWorker) {
  WatchState state;
  BlockingControls controls;
  WatchServerOptions o;
  o.bind = "0.0.0.0", o.port = 0, o.timeout_s = 30, o.most_streams = 2, o.token = newToken();  // 6 workers
  WatchServer server(state, o, &controls);
  server.start();
  Unfinished held(server.port(), 64, 4, 4, 0, 0, "?token=" + o.token);
  std::vector<int> busy;
  for (int i = 0; i < o.most_streams + 4; ++i) {
    busy.push_back(connectTo(server.port()));
    sendAll(busy.back(), "POST /control?command=play&token=" + o.token + " HTTP/1.1\r\nContent-Length: 0\r\n\r\n");
  }
  ASSERT_TRUE(eventually([&] {
    std::lock_guard<std::mutex> lock(controls.mutex);
    return controls.waiting == o.most_streams + 4;
  }));
  std::string refused;
  for (const std::string& request : std::vector<std::string>{"GET / HTTP/1.1\r\n\r\n", "GET /state?token=" + std::string(32, 'f') + " HTTP/1.1\r\n\r\n",
                                    "POST /control?command=play HTTP/1.1\r\nContent-Length: 0\r\n\r\n"}) {
    const int fd = connectTo(server.port());
    sendAll(fd, request);
    refused = answer(fd, 4096);  // (within 10 s, or "")
    close(fd);
    EXPECT_EQ(refused.rfind("HTTP/1.1 401", 0), 0u) << request << " answered " << refused;
    EXPECT_NE(refused.find("a token is required"), std::string::npos) << refused;
  }
  controls.release();
  for (int fd : busy) EXPECT_EQ(answer(fd, 4096).rfind("HTTP/1.1 200", 0), 0u), close(fd);
  EXPECT_EQ(held.stillWaiting(), static_cast<int>(held.waiting.size()));
  server.stop();
}

TEST(WatchServer, ASecondServerOnAPortInUseFailsNamingIt) {
  WatchState state;
  WatchServerOptions o;
  o.port = 0;
  WatchServer first(state, o);
  first.start();
  o.port = first.port();
  WatchServer second(state, o);
  try {
    second.start();
    ADD_FAILURE() << "a second server started on port " << o.port;
  } catch (const std::runtime_error& e) {
    const std::string said = e.what();
    EXPECT_NE(said.find("127.0.0.1:" + std::to_string(o.port)), std::string::npos) << said;
    EXPECT_NE(said.find("in use"), std::string::npos) << said;
  }
  httplib::Client client("127.0.0.1", first.port());
  for (int i = 0; i < 8; ++i) {  // every request still the first's (a shared port would hand some to the second)
    const auto res = client.Get("/state");
    ASSERT_TRUE(res);
    EXPECT_EQ(res->status, 200);
  }
  first.stop();
}

// Bounded: past `most_connections` waiting at once, the oldest is dropped, so a new client still gets in.
TEST(WatchServer, WhenFullTheOldestWaitingConnectionMakesRoom) {
  WatchState state;
  WatchServerOptions o;
  o.port = 0, o.timeout_s = 30, o.most_connections = 16;
  WatchServer server(state, o);
  server.start();
  std::vector<int> idle;
  for (int i = 0; i < 40; ++i) {
    idle.push_back(connectTo(server.port()));
    ASSERT_TRUE(eventually([&] { return server.connections().held == std::min<std::uint64_t>(i + 1, 16); }));
  }
  httplib::Client client("127.0.0.1", server.port());
  const auto res = client.Get("/");
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 200);
  // The GET's connection dropped one more: the first 25 are closed, the last 15 still wait.
  for (int i = 0; i < 40; ++i) {
    if (i < 25) EXPECT_TRUE(eventually([&] { return !open(idle[i]); })) << i;
    else EXPECT_TRUE(open(idle[i])) << i;
  }
  EXPECT_EQ(server.connections().dropped, 25u);
  for (int fd : idle) close(fd);
  server.stop();
}

// With no file left to take a connection with, the server waits for one (and drops what it holds to make
// one), instead of trying the listener again and again.
TEST(WatchServer, OutOfFilesItWaitsInsteadOfSpinning) {
  WatchState state;
  WatchServerOptions o;
  o.port = 0;
  WatchServer server(state, o);
  server.start();
  const int client = socket(AF_INET, SOCK_STREAM, 0);
  rlimit files{};
  getrlimit(RLIMIT_NOFILE, &files);
  const rlimit before = files;
  files.rlim_cur = static_cast<rlim_t>(client) + 64;
  setrlimit(RLIMIT_NOFILE, &files);
  std::vector<int> filler;
  for (int fd; (fd = dup(client)) >= 0;) filler.push_back(fd);
  sockaddr_in a = loopback(server.port());
  ASSERT_EQ(connect(client, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  const bool paused = eventually([&] { return server.connections().paused >= 5; }, 10);
  const StageCounts c = server.connections();
  for (int fd : filler) close(fd);
  setrlimit(RLIMIT_NOFILE, &before);
  EXPECT_TRUE(paused) << c.wakeups << " wake-ups";
  EXPECT_LE(c.wakeups, 4 * c.paused + 10) << "it spun on the listener";
  sendAll(client, "GET / HTTP/1.1\r\n\r\n");
  EXPECT_EQ(answer(client).rfind("HTTP/1.1 200", 0), 0u);
  close(client);
  server.stop();
}

}  // namespace
}  // namespace afford

namespace afford {
namespace {

// Runs heard end when their result is heard, whichever run is shown: an intrinsic or goals run's RESULT, an
// extrinsic test's EXTRINSIC_RESULT (a test's state stayed "running" before).
TEST(WatchState, EveryRunHeardEndsWithItsResultATestsToo) {
  const RunConfig c = test::shippedConfig();
  WatchState state;
  feedRun(state, "trained", 5, c);
  feedRun(state, "test-e0", 3, c);
  process_status_t running{};
  running.state = process_status_t::RUNNING;
  for (const char* run : {"trained", "test-e0"}) running.run_id = run, running.step = 2, state.onStatus(running);
  run_result_t trained{};
  trained.run_id = "trained", trained.step = 5;
  state.onResult(trained);  // not the run shown
  extrinsic_result_t tested{};
  tested.run_id = "test-e0", tested.step = 3;
  state.onExtrinsicResult(tested);
  state.onStatus(running);  // a heartbeat after the end changes nothing
  const json s = json::parse(state.snapshot(false));
  ASSERT_EQ(s["runs"].size(), 2u);
  for (const auto& r : s["runs"]) EXPECT_EQ(r["state"], "done") << r["id"];
  EXPECT_EQ(s["run"]["id"], "test-e0");
  EXPECT_EQ(s["step"], 3);  // (the other run's result did not move the step shown)
}

// The goals phase's trace: each module's competence after each goal that has a goal image, over its last
// 2 x goals.window goals; an exploration counts in the table, never in the trace.
TEST(WatchState, TheGoalsPhaseTracesEachModulesCompetence) {
  RunConfig c = test::shippedConfig();
  c.phase = Phase::Goals, c.goals.window = 2;
  WatchState state;
  feedRun(state, "goals", 1, c);
  const std::vector<std::pair<int, bool>> results = {{0, false}, {1, true}, {1, false}, {2, true}, {1, true},
                                                     {1, true},  {1, true}, {0, false}};
  int id = 0;
  for (const auto& [module, reached] : results) state.onGoalResult(10 + id, id, goalModuleName(module), reached), ++id;
  const json s = json::parse(state.snapshot(false));
  EXPECT_EQ(s["goal_window"], 2);
  const auto& trace = s["competence"];
  ASSERT_EQ(trace.size(), 6u);  // one point per goal of colour, move or colour and place
  EXPECT_EQ(trace[0], json::array({1.0, -1.0, -1.0}));
  EXPECT_EQ(trace[1], json::array({0.5, -1.0, -1.0}));
  EXPECT_EQ(trace[2], json::array({0.5, 1.0, -1.0}));
  EXPECT_EQ(trace[5], json::array({0.75, 1.0, -1.0}));  // the last 4 colour goals: 0, 1, 1, 1
  EXPECT_EQ(s["goals"][0]["module"], "explore");
  EXPECT_EQ(s["goals"][0]["ended"], 2);
}

// Bound to every address: the addresses printed are this machine's own, never 0.0.0.0 (which no browser
// opens), loopback among them (opened here; the others are not reached from a test).
TEST(WatchServer, BoundToEveryAddressItPrintsAddressesThatOpen) {
  WatchState state;
  WatchServerOptions o;
  o.bind = "0.0.0.0", o.port = 0, o.token = newToken();
  WatchServer server(state, o);
  server.start();
  const std::vector<std::string> urls = server.urls();
  ASSERT_FALSE(urls.empty());
  const std::string loopback = "http://127.0.0.1:" + std::to_string(server.port()) + "/?token=" + o.token;
  for (const std::string& u : urls) {
    EXPECT_EQ(u.find("0.0.0.0"), std::string::npos) << u;
    EXPECT_NE(u.find(":" + std::to_string(server.port()) + "/?token=" + o.token), std::string::npos) << u;
  }
  EXPECT_EQ(urls.back(), loopback);
  httplib::Client client("127.0.0.1", server.port());
  auto res = client.Get(("/state?token=" + o.token).c_str());
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 200);
  server.stop();
}

}  // namespace
}  // namespace afford
