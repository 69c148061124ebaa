// A run's log cut anywhere (issue 55): at every event boundary of a small
// recorded run, in the middle of events and after an event's header, with its
// manifest beside it and without. Replay never calls it equal to the record
// and says what is missing; explain refuses a cut test; the reader the
// viewers, export and the Python package share warns of it. The whole log
// replays equal. The runs are recorded once by `afford experiment` over memq
// (its logger writes the log and the manifest).
#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "afford/process_main.hpp"
#include "experiment/replay/explain.hpp"
#include "experiment/replay/replay.hpp"
#include "logger/logger.hpp"
#include "tests/support.hpp"
#include "viewer/step_order.hpp"

namespace afford {
namespace {

namespace fs = std::filesystem;

std::shared_ptr<spdlog::logger> quiet() {
  return std::make_shared<spdlog::logger>("log-cut-test", std::make_shared<spdlog::sinks::null_sink_mt>());
}

bool says(const std::vector<std::string>& lines, const std::string& what) {
  for (const auto& l : lines)
    if (l.find(what) != std::string::npos) return true;
  return false;
}

// Where the events of a log file begin, and its size last.
std::vector<std::int64_t> boundaries(const fs::path& file) {
  LogReader in(file, LogLimits{});
  std::vector<std::int64_t> at;
  for (LogEvent e; in.next(e);) at.push_back(e.offset);
  at.push_back(static_cast<std::int64_t>(fs::file_size(file)));
  return at;
}

// The points a log of these boundaries is cut at: every boundary but the end, in the middle of each event,
// just after the header of the first events, and one byte before the end.
std::vector<std::int64_t> cutPoints(const std::vector<std::int64_t>& at) {
  std::vector<std::int64_t> cuts;
  for (std::size_t i = 0; i + 1 < at.size(); ++i) {
    cuts.push_back(at[i]);
    if (i < 3) cuts.push_back(at[i] + 28);
    cuts.push_back((at[i] + at[i + 1]) / 2);
  }
  cuts.push_back(at.back() - 1);
  return cuts;
}

class LogCut : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = test::tempDir("log-cut");
    const auto r = test::runAfford("experiment base --system IMP --reps 1 --steps 5 --extrinsic-reps 1 --scenarios "
                                   "scenario1 --set planner.budget=2 --transport memq --quiet --progress none "
                                   "--run-prefix lc --no-reuse-agents --keep-logs all --out " + root_ + "/out "
                                   "--log-root " + logs());
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  static std::string logs() { return root_ + "/logs"; }
  static fs::path intrinsic() { return fs::path(logs()) / "lc-base-IMP-s1"; }
  static fs::path extrinsic() { return fs::path(logs()) / "lc-base-IMP-s1-scenario1-e0"; }
  // The first `bytes` of `run`'s log, as the log folder `name` in the same log root (an extrinsic test's
  // agent is read from there), with the run's manifest beside it or not.
  static fs::path cutCopy(const fs::path& run, const std::string& name, std::int64_t bytes, bool manifest) {
    const fs::path dir = fs::path(logs()) / name;
    fs::create_directories(dir);
    std::ifstream in(run / "log.00.lcm", std::ios::binary);
    std::string data(static_cast<std::size_t>(bytes), '\0');
    in.read(data.data(), bytes);
    std::ofstream(dir / "log.00.lcm", std::ios::binary | std::ios::trunc).write(data.data(), bytes);
    fs::remove(dir / "manifest.json");
    if (manifest) fs::copy_file(run / "manifest.json", dir / "manifest.json");
    return dir;
  }
  static std::string root_;
};
std::string LogCut::root_;

// Replay of a cut log is never ok and says what is missing; when the RUN_CONFIG itself is gone the error says it.
// `into`: the processes replayed (the decider alone is quick: what is missing does not depend on them).
void expectReplaySaysMissing(const fs::path& dir, const std::string& where, std::vector<std::string> into = {}) {
  ReplayOptions o;
  o.log_dir = dir.string();
  o.into = std::move(into);
  try {
    const ReplayResult r = replayRun(o, *quiet());
    EXPECT_FALSE(r.ok()) << where;
    EXPECT_TRUE(says(r.cut, "missing")) << where << ": " << joinedCut(r.cut);
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("the log is cut: "), std::string::npos) << where << ": " << what;
    EXPECT_NE(what.find("missing"), std::string::npos) << where << ": " << what;
  }
}

TEST_F(LogCut, TheWholeLogsReplayEqualWithAndWithoutTheirManifest) {
  for (const fs::path& run : {intrinsic(), extrinsic()})
    for (bool manifest : {true, false}) {
      const auto size = static_cast<std::int64_t>(fs::file_size(run / "log.00.lcm"));
      const fs::path copy = cutCopy(run, "whole", size, manifest);
      ReplayOptions o;
      o.log_dir = copy.string();
      const ReplayResult r = replayRun(o, *quiet());
      EXPECT_TRUE(r.ok()) << run << (manifest ? " with" : " without") << " its manifest: " << joinedCut(r.cut);
      EXPECT_TRUE(r.cut.empty()) << joinedCut(r.cut);
    }
}

TEST_F(LogCut, AnIntrinsicLogCutAnywhereIsNeverEqualToTheRecord) {
  const std::vector<std::int64_t> at = boundaries(intrinsic() / "log.00.lcm");
  ASSERT_GT(at.size(), 25u);
  for (const std::int64_t bytes : cutPoints(at))
    for (bool manifest : {true, false})
      expectReplaySaysMissing(cutCopy(intrinsic(), "cut", bytes, manifest),
                              "cut at byte " + std::to_string(bytes) + (manifest ? " with" : " without") + " manifest",
                              {"motivation"});
}

TEST_F(LogCut, AnExtrinsicLogCutAnywhereIsNeverEqualToTheRecordAndExplainRefusesIt) {
  const std::vector<std::int64_t> at = boundaries(extrinsic() / "log.00.lcm");
  ASSERT_GT(at.size(), 10u);
  for (const std::int64_t bytes : cutPoints(at))
    for (bool manifest : {true, false}) {
      const std::string where =
          "cut at byte " + std::to_string(bytes) + (manifest ? " with" : " without") + " manifest";
      const fs::path copy = cutCopy(extrinsic(), "cut-test", bytes, manifest);
      expectReplaySaysMissing(copy, where, {"planner"});
      try {
        explainLog(copy.string(), "", *quiet());
        ADD_FAILURE() << where << ": explained";
      } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("missing"), std::string::npos) << where << ": " << e.what();
      }
    }
  EXPECT_NO_THROW(explainLog(extrinsic().string(), "", *quiet()));
}

// How much is missing, in the words replay prints: by the manifest's count, and by the run's own steps and end.
TEST_F(LogCut, ReplaySaysHowMuchIsMissing) {
  const std::vector<std::int64_t> at = boundaries(intrinsic() / "log.00.lcm");
  const std::int64_t events = static_cast<std::int64_t>(at.size()) - 1;
  const std::int64_t half = events / 2;
  ReplayOptions o;
  o.log_dir = cutCopy(intrinsic(), "half", at[static_cast<std::size_t>(half)], true).string();
  ReplayResult r = replayRun(o, *quiet());
  EXPECT_TRUE(says(r.cut, "its manifest counts " + std::to_string(events) + " events")) << joinedCut(r.cut);
  EXPECT_TRUE(says(r.cut, ": " + std::to_string(events - half) + " events missing")) << joinedCut(r.cut);
  EXPECT_TRUE(says(r.cut, " of 5: ")) << joinedCut(r.cut);
  EXPECT_TRUE(says(r.cut, "the run's end is not in the log: its RESULT and STOP are missing")) << joinedCut(r.cut);
  // Only the STOP cut off, without the manifest: the log itself tells.
  o.log_dir = cutCopy(intrinsic(), "no-stop", at[static_cast<std::size_t>(events - 1)], false).string();
  r = replayRun(o, *quiet());
  EXPECT_EQ(r.cut,
            std::vector<std::string>{"the run's end is not all in the log: the STOP after its RESULT is missing"});
  // Nothing left but the manifest.
  o.log_dir = cutCopy(intrinsic(), "empty", 0, true).string();
  try {
    replayRun(o, *quiet());
    ADD_FAILURE() << "an empty log replayed";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(std::to_string(events) + " events missing"), std::string::npos) << e.what();
  }
}

// The command: exit 1 and the missing lines on a cut log (never "equals the record"), exit 0 on the whole one.
TEST_F(LogCut, TheReplayCommandSaysTheLogIsCutAndFails) {
  const std::vector<std::int64_t> at = boundaries(intrinsic() / "log.00.lcm");
  const std::int64_t size = at.back();
  // Empty, after the first header, on a boundary midway, before the STOP, in the middle of the STOP.
  for (const std::int64_t bytes : {std::int64_t{0}, std::int64_t{28}, at[at.size() / 2], at[at.size() - 2], size - 1})
    for (bool manifest : {true, false}) {
      const fs::path copy = cutCopy(intrinsic(), "cli", bytes, manifest);
      const auto r = test::runAfford("replay " + copy.string());
      EXPECT_NE(r.exit_code, 0) << bytes << " " << manifest << "\n" << r.output;
      EXPECT_NE(r.output.find("the log is cut: "), std::string::npos) << r.output;
      EXPECT_NE(r.output.find("missing"), std::string::npos) << r.output;
      EXPECT_EQ(r.output.find("equals the record"), std::string::npos) << r.output;
    }
  const auto whole = test::runAfford("replay " + intrinsic().string());
  EXPECT_EQ(whole.exit_code, 0) << whole.output;
  EXPECT_NE(whole.output.find("replay equals the record"), std::string::npos) << whole.output;
  EXPECT_EQ(whole.output.find("the log is cut"), std::string::npos) << whole.output;
}

// What `afford watch --log`, `afford render`, `afford export` and `afford.read_log` read a log through says it
// is cut, at once; and export says so in its summary.
TEST_F(LogCut, TheViewersReaderWarnsOfACutLog) {
  const std::vector<std::int64_t> at = boundaries(intrinsic() / "log.00.lcm");
  const auto cutOf = [](const fs::path& dir) {
    StepOrderedLog<RecordedLogStream, RunSelector> in(
        [&](spdlog::logger& l) { return std::make_unique<RecordedLogStream>(dir, l); },
        [&](spdlog::logger& l) { return std::make_unique<RunSelector>("", dir.string(), l); },
        loadProtocol(defaultConfigDir()), *quiet());
    return in.cut();
  };
  for (std::size_t i = 1; i + 1 < at.size(); i += 7)
    for (bool manifest : {true, false}) {
      const auto cut = cutOf(cutCopy(intrinsic(), "viewer", at[i] + 30, manifest));
      EXPECT_TRUE(says(cut, "missing")) << "cut at byte " << at[i] + 30 << ": " << joinedCut(cut);
    }
  EXPECT_TRUE(cutOf(intrinsic()).empty()) << joinedCut(cutOf(intrinsic()));
  const fs::path copy = cutCopy(intrinsic(), "export", at[at.size() / 2], true);
  const auto r = test::runAfford("export " + copy.string() + " --mcap " + root_ + "/cut.mcap");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("[warning] the log is cut: its manifest counts"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("so the file holds the run only as far as the log goes"), std::string::npos) << r.output;
}

// A log of two segments (a logger restarted mid-run): its manifest counts the last one. Whole, it replays
// equal; its last segment cut or gone, replay says what is missing; its first one cut, the serials after it say.
TEST_F(LogCut, ALogOfTwoSegmentsIsCheckedSegmentBySegment) {
  const auto events = readRecordedLog(intrinsic(), *quiet()).events;
  std::ifstream min(intrinsic() / "manifest.json");
  nlohmann::json manifest = nlohmann::json::parse(min);
  manifest["segments"] = nlohmann::json::array();  // (as the logger begins one)
  const auto twoSegments = [&](const std::string& name, std::size_t split, std::size_t drop_at) {
    const fs::path dir = fs::path(logs()) / name;
    fs::remove_all(dir);
    {
      RunLog first(dir.string(), manifest);
      for (std::size_t i = 0; i < split; ++i)
        if (i != drop_at) first.write(events[i].channel, events[i].data.data(), events[i].data.size(), events[i].utime);
    }  // (killed: closed as incomplete)
    RunLog second(dir.string(), manifest);
    for (std::size_t i = split; i < events.size(); ++i)
      if (i != drop_at) second.write(events[i].channel, events[i].data.data(), events[i].data.size(), events[i].utime);
    second.close();
    return dir;
  };
  const std::size_t split = events.size() / 3;
  ReplayOptions o;
  o.log_dir = twoSegments("two", split, events.size()).string();
  EXPECT_TRUE(replayRun(o, *quiet()).ok());
  const fs::path last = fs::path(o.log_dir) / "log.01.lcm";
  fs::resize_file(last, fs::file_size(last) - 100);
  expectReplaySaysMissing(o.log_dir, "the last segment cut");
  fs::remove(last);
  expectReplaySaysMissing(o.log_dir, "the last segment gone");
  o.log_dir = twoSegments("first-cut", split, split - 5).string();  // an event gone from the first segment
  const ReplayResult r = replayRun(o, *quiet());
  EXPECT_FALSE(r.ok());
  EXPECT_FALSE(r.gaps.empty());
}

}  // namespace
}  // namespace afford
