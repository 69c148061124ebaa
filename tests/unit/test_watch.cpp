// afford watch's state and page server (experiment/watch/): bounded whatever
// the run's length, a page that stops reading holds nothing, off loopback a
// token is required, and bad requests are refused without holding memory.
#include <gtest/gtest.h>
#include <httplib.h>
#include <netinet/in.h>
#include <nlohmann/json.hpp>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
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

// A raw client socket on the server's port.
int connectTo(int port) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
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
  EXPECT_NE(server.url().find("?token=" + o.token), std::string::npos);
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
    for (const auto& a : answers) EXPECT_TRUE(a.empty() || a.rfind("HTTP/1.1 400", 0) == 0) << a;
  }

  // A request that never ends is dropped after the read timeout.
  int fd = connectTo(server.port());
  sendAll(fd, "GET /state HTTP/1.1\r\nX-Slow: ");
  const std::string slow = answer(fd);
  EXPECT_TRUE(slow.empty() || slow.rfind("HTTP/1.1 400", 0) == 0) << slow;
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

}  // namespace
}  // namespace afford
