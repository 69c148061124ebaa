#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <set>
#include <tuple>

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

}  // namespace
}  // namespace afford
