// The logger killed near a run's end and started again only after the run's last step, killed once more while it
// catches up, or killed with its log open after the run's STOP: the runner gives it the run again, it goes on
// from its log's segments, asks for the rest (its peers hold it: the runner stops the run only once the log holds
// all that was published), and closes the log; the run completes and its log replays to the run's weights. In
// one process over memq (the same node code as the executables), without timing: the kills follow the run's
// steps, its RESULT and its STOP.
#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>

#include <filesystem>
#include <memory>
#include <sstream>

#include "afford/processes.hpp"
#include "afford/protocol.hpp"
#include "afford/run_control_t.hpp"
#include "experiment/run/driver.hpp"
#include "experiment/run/host.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {

namespace fs = std::filesystem;

// When the logger is killed, and when it is started again.
enum class Fault {
  AfterTheEnd,       // killed at a step, started again once the run's RESULT is out
  TwiceAfterTheEnd,  // ... and killed once more (started at once) when it has caught up half of what it missed
  OnTheStop,         // killed just after it took the run's STOP (its log open), started again at once
};

struct RunWithLoggerKilled {
  std::ostringstream log;
  RunOutcome outcome;
  std::string root, dir;
  int starts = 1;  // of the logger

  RunWithLoggerKilled(const std::string& name, std::int64_t steps, std::int64_t kill_at, Fault fault)
      : root(test::tempDir(name)), dir(root + "/" + name) {
    lcm::LCM lcm("memq://");
    auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(log);
    auto logger = [&](const std::string& process) {
      auto l = std::make_shared<spdlog::logger>(process, sink);
      l->set_pattern("[%n] %v");
      return l;
    };
    const ProtocolConfig protocol = test::shippedProtocol();
    const HostOptions options{/*single_thread=*/false, root, nullptr, ""};
    InProcessHost host(lcm, protocol, logger, options);
    host.start(runProcesses(Phase::Intrinsic, /*recorded=*/false));
    auto startLogger = [&] { return makeNode("logger", lcm, logger("logger"), protocol, options); };
    std::unique_ptr<NodeBase> lg = startLogger();
    RunDriver driver(lcm, logger("runner"), protocol);
    struct Tap {
      bool result = false, stopped = false;  // the run's RESULT, the runner's STOP went out
      void on(const lcm::ReceiveBuffer* b, const std::string& channel) {
        run_control_t c;
        if (channel == ch::result.name) result = true;
        if (channel == ch::runControl.name && c.decode(b->data, 0, static_cast<int>(b->data_size)) > 0 &&
            c.command == run_control_t::STOP)
          stopped = true;
      }
    } tap;
    lcm.subscribe(ch::result.name, &Tap::on, &tap);
    lcm.subscribe(ch::runControl.name, &Tap::on, &tap);
    enum class Stage { Alive, Dead, CatchingUp, Restarted } stage = Stage::Alive;
    const std::int64_t half = kill_at + (steps - kill_at) / 2;
    auto pump = [&] {
      while (lcm.handleTimeout(0) > 0) {  // one message at a time: the kills fall between two messages
        if (stage == Stage::Alive && fault != Fault::OnTheStop && host.node("environment").lastStep() >= kill_at) {
          lg.reset();  // killed: what was in flight to it is lost
          stage = Stage::Dead;
        } else if (stage == Stage::Alive && fault == Fault::OnTheStop && tap.stopped) {
          lg = startLogger();  // killed with its log open (it waits for its peers' final counts), started again
          ++starts;
          stage = Stage::Restarted;
        } else if (stage == Stage::Dead && tap.result) {
          lg = startLogger();
          ++starts;
          stage = fault == Fault::TwiceAfterTheEnd ? Stage::CatchingUp : Stage::Restarted;
        } else if (stage == Stage::CatchingUp && lg->state() == process_status_t::RUNNING && lg->lastStep() >= half) {
          lg = startLogger();  // killed while it catches up, and started again at once
          ++starts;
          stage = Stage::Restarted;
        }
      }
      lcm.handleTimeout(2);
      host.tick();
      if (lg) lg->tick();
    };
    RunSpec spec;
    spec.run_id = name;
    spec.experiment = "base";
    spec.system = "IMP";
    spec.seed = 3;
    spec.steps = steps;
    // A short close_timeout_ms: a runner that does not wait for the restarted logger fails the run soon.
    spec.config_yaml = test::shippedConfigYaml("base", System::IMP, 3, steps,
                                               {"protocol.close_timeout_ms=3000", "protocol.stop_grace_ms=1000"});
    spec.processes = runProcesses(Phase::Intrinsic, /*recorded=*/true);
    spec.log_root = root;
    spec.stall_seconds = 20;
    outcome = driver.run(spec, pump, [] { return std::string(); });
    for (int i = 0; i < 500 && host.inRun(); ++i) pump();
  }
};

void expectWholeAndReplayed(const RunWithLoggerKilled& r, int starts) {
  ASSERT_TRUE(r.outcome.ok) << r.outcome.error << "\n" << r.log.str().substr(0, 4000);
  EXPECT_EQ(r.starts, starts);
  EXPECT_EQ(r.outcome.log_dir, r.dir);
  const nlohmann::json m = test::readJson(fs::path(r.dir) / "manifest.json");
  EXPECT_TRUE(m["complete"].get<bool>()) << m.dump(2);
  EXPECT_EQ(m["segments"].size(), static_cast<std::size_t>(starts)) << m.dump(2);
  const auto replay = test::runAfford("replay " + r.dir);
  EXPECT_EQ(replay.exit_code, 0) << replay.output;
  EXPECT_NE(replay.output.find("replay equals the record"), std::string::npos) << replay.output;
  EXPECT_NE(replay.output.find("weights_checksum: " + r.outcome.weights_checksum), std::string::npos) << replay.output;
}

TEST(LoggerRestart, KilledNearTheEndAndStartedAfterTheRunsResultTheRunCompletesAndItsLogReplays) {
  const RunWithLoggerKilled r("logger-after-the-end", 400, 350, Fault::AfterTheEnd);
  expectWholeAndReplayed(r, 2);
  EXPECT_NE(r.log.str().find("process logger is free again (restarted?)"), std::string::npos);
}

TEST(LoggerRestart, KilledAgainWhileItCatchesUpTheRunCompletesAndItsLogReplays) {
  const RunWithLoggerKilled r("logger-twice", 400, 250, Fault::TwiceAfterTheEnd);
  expectWholeAndReplayed(r, 3);
}

TEST(LoggerRestart, KilledWithItsLogOpenAfterTheStopTheRunCompletesAndItsLogReplays) {
  const RunWithLoggerKilled r("logger-on-the-stop", 400, 0, Fault::OnTheStop);
  expectWholeAndReplayed(r, 2);
  EXPECT_NE(r.log.str().find("the logger is free again (restarted?) before it closed the run's log"), std::string::npos);
}

}  // namespace
}  // namespace afford
