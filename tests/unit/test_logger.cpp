#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <set>
#include <tuple>

#include <chrono>
#include <thread>

#include "afford/decision_t.hpp"
#include "afford/process_status_t.hpp"
#include "afford/run_result_t.hpp"
#include "afford/seal.hpp"
#include "afford/wire_bounds.hpp"
#include "logger/logger.hpp"
#include "logger/node.hpp"
#include "afford/run_config_t.hpp"
#include "afford/run_control_t.hpp"
#include <spdlog/sinks/null_sink.h>
#include "tests/samples.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {

namespace fs = std::filesystem;

nlohmann::json manifestOf(const fs::path& dir) {
  std::ifstream in(dir / "manifest.json");
  return nlohmann::json::parse(in);
}

TEST(RunLog, WritesAStandardLcmLogAndAManifest) {
  const fs::path dir = fs::path(test::tempDir("runlog")) / "run-a";
  {
    RunLog log(dir.string(), {{"run_id", "run-a"}, {"seed", 4}});
    const std::uint8_t a[] = {1, 2, 3}, b[] = {9};
    log.write("FOCUS", a, sizeof a, 100);
    log.write("DECISION", b, sizeof b, 200);
    log.sawProcess("eye", 42);
    log.close();
  }
  const auto events = test::readLog((dir / "log.00.lcm").string());
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].channel, "FOCUS");
  EXPECT_EQ(events[0].data, (std::vector<std::uint8_t>{1, 2, 3}));
  EXPECT_EQ(events[1].channel, "DECISION");
  const auto m = manifestOf(dir);
  EXPECT_EQ(m["run_id"], "run-a");
  EXPECT_EQ(m["events"], 2);
  EXPECT_EQ(m["complete"], true);
  EXPECT_EQ(m["processes"][0]["process"], "eye");
  EXPECT_EQ(m["segments"], nlohmann::json({"log.00.lcm"}));
}

TEST(RunLog, EveryEventIsOnDiskAsSoonAsItIsWritten) {
  const fs::path dir = fs::path(test::tempDir("runlog-flush")) / "run-b";
  RunLog log(dir.string(), {{"run_id", "run-b"}});
  const std::uint8_t a[] = {7, 7};
  log.write("SCENE", a, sizeof a, 1);
  EXPECT_EQ(test::readLog((dir / "log.00.lcm").string()).size(), 1u);  // before close
}

TEST(RunLog, RefusesTheFolderOfACompletedRun) {
  const fs::path dir = fs::path(test::tempDir("runlog-done")) / "run-c";
  { RunLog(dir.string(), {{"run_id", "run-c"}}).close(); }
  EXPECT_THROW(RunLog(dir.string(), {{"run_id", "run-c"}}), std::runtime_error);
}

TEST(RunLog, ContinuesAnUnfinishedRunAsANewSegment) {
  const fs::path dir = fs::path(test::tempDir("runlog-seg")) / "run-d";
  fs::create_directories(dir);
  std::ofstream(dir / "log.00.lcm") << "";
  std::ofstream(dir / "manifest.json") << R"({"run_id": "run-d", "complete": false})";
  RunLog log(dir.string(), {{"run_id", "run-d"}});
  EXPECT_EQ(fs::path(log.path()).filename(), "log.01.lcm");
}

// ---- the run header the logger reads without decoding (peekRunHeader) ----------

// Every serial-carrying type, encoded as its publisher sends it, read back.
template <class Msg>
void expectHeaderRead(std::set<std::string>& seen) {
  Msg m = test::sample<Msg>();
  m.run_id = "a-run-id-of-some-length-" + std::string(wire::Bounds<Msg>::kName);
  m.step = 123456789;
  m.serial = 987654321;
  const std::vector<std::uint8_t> bytes = sealed(m);
  RunHeader h;
  ASSERT_TRUE(peekRunHeader(bytes.data(), static_cast<std::uint32_t>(bytes.size()), h)) << wire::Bounds<Msg>::kName;
  EXPECT_EQ(h.run_id, m.run_id) << wire::Bounds<Msg>::kName;
  EXPECT_EQ(h.step, m.step) << wire::Bounds<Msg>::kName;
  EXPECT_EQ(h.serial, m.serial) << wire::Bounds<Msg>::kName;
  seen.insert(wire::Bounds<Msg>::kName);
}

TEST(RunHeader, IsReadFromEverySerialCarryingType) {
  std::set<std::string> seen;
  std::apply([&](auto... m) { (expectHeaderRead<decltype(m)>(seen), ...); }, wire::SerialTypes{});
  EXPECT_EQ(seen.size(), std::tuple_size_v<wire::SerialTypes>);
  EXPECT_EQ(seen.size(), channelNames(/*serial_only=*/true).size()) << "one serial-carrying type per serial channel";
}

TEST(RunHeader, IsNotReadFromABufferTooShortForIt) {
  focus_t m = test::sample<focus_t>();
  const std::vector<std::uint8_t> bytes = sealed(m);
  const std::size_t header = 8 + 4 + m.run_id.size() + 1 + 8 + 8;  // fingerprint, run_id, step, serial
  RunHeader h;
  for (std::size_t n = 0; n < header; ++n)
    EXPECT_FALSE(peekRunHeader(bytes.data(), static_cast<std::uint32_t>(n), h)) << n << " bytes";
  EXPECT_TRUE(peekRunHeader(bytes.data(), static_cast<std::uint32_t>(header), h));
}

TEST(RunHeader, TheSerialChannelsAreThoseOfTheSerialTypes) {
  for (const std::string& c : channelNames(/*serial_only=*/true)) EXPECT_TRUE(isSerialChannel(c)) << c;
  for (const char* c : {ch::runConfig.name, ch::runControl.name, ch::status.name, ch::resend.name})
    EXPECT_FALSE(isSerialChannel(c)) << c;
}

// A flood of distinct RUN_CONTROL messages of the run (each a perfect message)
// is recorded up to protocol.limits.control_messages, then only counted: the
// logger's memory and the log stay bounded, and the manifest says how many.
TEST(LoggerNode, RecordsAtMostTheControlMessagesItsLimitAllowsAndCountsTheRest) {
  const std::string root = test::tempDir("logger-control");
  lcm::LCM lcm("memq://");
  const ProtocolConfig protocol = test::shippedProtocol();
  auto quiet = std::make_shared<spdlog::logger>("logger", std::make_shared<spdlog::sinks::null_sink_mt>());
  LoggerNode logger(lcm, quiet, protocol, root);
  Edge runner(lcm, quiet, "runner", protocol);
  auto pump = [&] {
    while (lcm.handleTimeout(0) > 0) {
    }
    logger.tick();
  };
  const std::string yaml = test::shippedConfigYaml("base", System::IMP, 1, 100);
  run_config_t rc;
  rc.run_id = "flooded";
  rc.step = 0;
  rc.request = 1;
  rc.seed = 1;
  rc.experiment = "base";
  rc.system = "IMP";
  rc.config_yaml = yaml;
  runner.send(ch::runConfig, rc);
  pump();
  ASSERT_EQ(logger.runId(), "flooded");
  const int flood = 5 * protocol.limits.control_messages;
  run_control_t c;
  c.run_id = "flooded";
  c.command = run_control_t::START;
  c.config_digest = rc.digest;  // (set as it was sent)
  for (int i = 0; i < flood; ++i) {
    c.step = i;
    runner.send(ch::runControl, c);
    pump();
  }
  c.command = run_control_t::STOP;
  c.step = 100;
  runner.send(ch::runControl, c);
  pump();
  ASSERT_TRUE(logger.runId().empty()) << "the logger did not leave the run";
  int recorded = 0;
  for (const auto& e : test::readLog(root + "/flooded/log.00.lcm"))
    recorded += e.channel == ch::runConfig.name || e.channel == ch::runControl.name;
  EXPECT_EQ(recorded, protocol.limits.control_messages);
  const auto m = manifestOf(fs::path(root) / "flooded");
  // Recorded: the config and control_messages - 1 STARTs; the STOP and the other STARTs counted.
  EXPECT_EQ(m["control_dropped"], flood + 1 - (protocol.limits.control_messages - 1));
}

// A logger in a run on memq: a runner's edge says RUN_CONFIG, RUN_CONTROL and the motivation's STATUS; the
// motivation's DECISIONs were published before the logger joined, so its log lacks them until they are fed
// again (as a publisher answers a RESEND: the motivation here answers none by itself).
struct LoggerInARun {
  std::string root;
  lcm::LCM lcm{"memq://"};
  ProtocolConfig protocol = test::shippedProtocol();
  std::shared_ptr<spdlog::logger> quiet =
      std::make_shared<spdlog::logger>("logger", std::make_shared<spdlog::sinks::null_sink_mt>());
  std::unique_ptr<LoggerNode> logger;
  Edge runner{lcm, quiet, "runner", protocol};
  Edge motivation{lcm, quiet, "motivation", protocol};
  run_config_t rc;
  RunConfig config;
  std::vector<std::vector<std::uint8_t>> decisions;  // as published, before the logger joined the run
  std::vector<process_status_t> said;                // the logger's STATUS
  std::int64_t beat = 0;

  struct Tap {
    LoggerInARun* t;
    void on(const lcm::ReceiveBuffer* b, const std::string& channel) {
      const auto* d = static_cast<const std::uint8_t*>(b->data);
      process_status_t st{};
      if (channel == ch::decision.name) {
        if (t->logger->runId().empty()) t->decisions.emplace_back(d, d + b->data_size);  // (not those fed again)
      }
      else if (st.decode(b->data, 0, static_cast<int>(b->data_size)) > 0 && st.process == "logger")
        t->said.push_back(st);
    }
  } tap{this};

  LoggerInARun(const std::string& name, int decisions_before, const std::vector<std::string>& settings = {})
      : root(test::tempDir(name)) {
    lcm.subscribe(ch::decision.name, &Tap::on, &tap);
    lcm.subscribe(ch::status.name, &Tap::on, &tap);
    logger = std::make_unique<LoggerNode>(lcm, quiet, protocol, root);
    rc = test::sample<run_config_t>();  // base, IMP, seed 1
    rc.run_id = name;
    rc.request = 1;
    rc.config_yaml = test::shippedConfigYaml("base", System::IMP, 1, 100, settings);
    sealed(rc);  // its digest: where the run's chains start
    config = parseRunConfigText(rc.config_yaml);
    motivation.join(rc.run_id, &config, requestOf(rc));
    for (int k = 0; k < decisions_before; ++k) {
      decision_t d = test::sample<decision_t>();
      d.run_id = rc.run_id;
      d.step = k;
      motivation.publish(ch::decision, d);
    }
    pump();  // (the logger serves no run yet: it takes none of them)
    runner.send(ch::runConfig, rc);
    pump();
    control(run_control_t::START);
  }
  void pump() {
    while (lcm.handleTimeout(0) > 0) {
    }
    if (logger) logger->tick();
  }
  // Pump for `ms` milliseconds, or until the logger has left the run.
  void pumpFor(int ms) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
    while (std::chrono::steady_clock::now() < until && !logger->runId().empty()) {
      pump();
      lcm.handleTimeout(5);
    }
  }
  void control(int8_t command) {
    run_control_t c;
    c.run_id = rc.run_id;
    c.step = command == run_control_t::STOP ? 100 : 0;
    c.command = command;
    c.config_digest = rc.digest;
    runner.send(ch::runControl, c);
    pump();
  }
  // The motivation's STATUS: in the run, or (left) free again with its final counts.
  void motivationSays(bool left) {
    process_status_t st{};
    st.run_id = left ? "" : rc.run_id;
    st.step = left ? -1 : static_cast<std::int64_t>(decisions.size()) - 1;
    st.process = "motivation";
    st.pid = 777;
    st.beat = beat++;
    st.state = left ? process_status_t::WAITING : process_status_t::RUNNING;
    st.config_digest = left ? 0 : rc.digest;
    st.counts_run = rc.run_id;
    st.counts_config = rc.digest;
    st.channels = {ch::decision.name};
    st.counts = {static_cast<std::int64_t>(decisions.size())};
    st.held_from = {0};
    st.n_channels = 1;
    st.n_takes = 0;
    runner.send(ch::status, st);
    pump();
  }
  void feed(std::size_t k) {
    lcm.publish(ch::decision.name, decisions[k].data(), static_cast<unsigned>(decisions[k].size()));
    pump();
  }
  int recordedDecisions() const {
    int n = 0;
    for (const auto& e : test::readLog(root + "/" + rc.run_id + "/log.00.lcm")) n += e.channel == ch::decision.name;
    return n;
  }
  nlohmann::json manifest() const { return manifestOf(fs::path(root) / rc.run_id); }
};

// After STOP the logger waits for what it misses while it keeps coming, however long the whole takes: the
// grace (protocol.stop_grace_ms) runs from the last message taken, not from the STOP. Here six missing
// DECISIONs come 300 ms apart, 1.5 s in all, with a grace of 1 s.
TEST(LoggerNode, AfterStopWaitsForMissingMessagesWhileTheyKeepComing) {
  LoggerInARun t("logger-slow-close", 6, {"protocol.stop_grace_ms=1000"});
  t.motivationSays(/*left=*/false);  // its counts: six published, none of them in the log
  t.control(run_control_t::STOP);
  t.motivationSays(/*left=*/true);
  ASSERT_FALSE(t.logger->runId().empty()) << "it left with six messages missing";
  for (std::size_t k = 0; k + 1 < t.decisions.size(); ++k) {
    t.feed(k);
    t.pumpFor(300);
    ASSERT_FALSE(t.logger->runId().empty()) << "it closed the log with DECISION " << k + 1 << ".. still coming";
  }
  t.feed(t.decisions.size() - 1);
  t.pumpFor(3000);
  ASSERT_TRUE(t.logger->runId().empty()) << "it did not close the log once nothing was missing";
  EXPECT_EQ(t.recordedDecisions(), 6);
  EXPECT_TRUE(t.manifest()["missing"].empty()) << t.manifest().dump(2);
}

// A logger paused (SIGSTOP) after it took STOP, while it still missed a message: its grace did not run while it
// could do nothing. Resumed past the grace, it asks again, takes the message, and closes the log whole.
TEST(LoggerNode, PausedWhileItClosesTheLogItStillTakesWhatIsMissingAfterThePause) {
  LoggerInARun t("logger-paused-close", 1, {"protocol.stop_grace_ms=1000"});
  t.motivationSays(/*left=*/false);
  t.control(run_control_t::STOP);
  t.motivationSays(/*left=*/true);
  ASSERT_FALSE(t.logger->runId().empty());
  // The pause: nothing runs in the logger for longer than its grace (and a heartbeat).
  std::this_thread::sleep_for(std::chrono::milliseconds(1600));
  t.logger->tick();  // its loop goes on: the answer to what it asks again comes after
  ASSERT_FALSE(t.logger->runId().empty()) << "it closed the log at once after the pause, a message missing";
  t.feed(0);
  t.pumpFor(3000);
  ASSERT_TRUE(t.logger->runId().empty());
  EXPECT_EQ(t.recordedDecisions(), 1);
  EXPECT_TRUE(t.manifest()["missing"].empty()) << t.manifest().dump(2);
}

// The STOP never reached the logger (paused through it, its datagram dropped), and the runner is gone: a
// publisher free again with its final counts says the run was stopped. The logger closes the log and is free.
TEST(LoggerNode, LeavesTheRunWhenAPublisherLeftItThoughNoStopCameHere) {
  LoggerInARun t("logger-no-stop", 0);
  t.motivationSays(/*left=*/false);
  t.motivationSays(/*left=*/true);
  ASSERT_TRUE(t.logger->runId().empty()) << "the logger stays in a run its peers have left";
  EXPECT_EQ(t.logger->state(), std::int8_t{process_status_t::WAITING});
  bool done = false;
  for (const auto& st : t.said) done = done || (st.state == process_status_t::DONE && st.detail == t.root + "/" + t.rc.run_id);
  EXPECT_TRUE(done) << "no DONE naming the log's folder";
  EXPECT_FALSE(t.manifest()["complete"].get<bool>());
  EXPECT_NE(t.manifest()["incomplete"].get<std::string>().find("the run did not end"), std::string::npos);
}

// A logger killed after it closed the run's log complete, before its DONE went out, and started again: the run
// is given to it again (the runner has not heard DONE). It records nothing, says DONE, and the log stays whole.
TEST(LoggerNode, StartedAgainAfterAnEarlierOneClosedTheLogCompleteItSaysDone) {
  LoggerInARun t("logger-closed-before", 0);
  Edge predictors(t.lcm, t.quiet, "predictors", t.protocol);
  predictors.join(t.rc.run_id, &t.config, requestOf(t.rc));
  run_result_t r = test::sample<run_result_t>();
  r.run_id = t.rc.run_id;
  r.step = 99;
  predictors.publish(ch::result, r);
  t.pump();
  t.control(run_control_t::STOP);
  ASSERT_TRUE(t.logger->runId().empty());
  ASSERT_TRUE(t.manifest()["complete"].get<bool>()) << t.manifest().dump(2);
  const std::string before = test::slurp(fs::path(t.root) / t.rc.run_id / "manifest.json");
  t.logger = std::make_unique<LoggerNode>(t.lcm, t.quiet, t.protocol, t.root);  // started again
  t.said.clear();
  t.runner.send(ch::runConfig, t.rc);
  t.pump();
  t.control(run_control_t::START);
  t.control(run_control_t::STOP);
  for (const auto& st : t.said) EXPECT_NE(st.state, std::int8_t{process_status_t::FAILED}) << st.detail;
  ASSERT_FALSE(t.said.empty());
  bool done = false;
  for (const auto& st : t.said) done = done || (st.state == process_status_t::DONE && st.detail == t.root + "/" + t.rc.run_id);
  EXPECT_TRUE(done) << "no DONE naming the log's folder";
  EXPECT_EQ(test::slurp(fs::path(t.root) / t.rc.run_id / "manifest.json"), before) << "the closed log was touched";
  EXPECT_FALSE(fs::exists(fs::path(t.root) / t.rc.run_id / "log.01.lcm"));
}

}  // namespace
}  // namespace afford
