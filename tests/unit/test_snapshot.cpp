// Runs of any length (docs/processes-and-channels.md): a process's snapshot
// file is read back as written, a damaged, cut or foreign one is refused
// naming the field, and a writer killed while it writes (itself or the forked
// copy of its process) leaves the earlier snapshot whole; a publisher holds what it published only until every reader
// of the run has a snapshot after it (and never more than history_mb), and a
// receiver that needs what was let go fails naming the channel.
#include <gtest/gtest.h>

#include <algorithm>
#include <signal.h>
#include <spdlog/sinks/null_sink.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "afford/decision_t.hpp"
#include "afford/edge.hpp"
#include "afford/edge_outbound.hpp"
#include "afford/process_status_t.hpp"
#include "afford/protocol.hpp"
#include "afford/resend_t.hpp"
#include "afford/seal.hpp"
#include "afford/snapshot.hpp"
#include "afford/version.hpp"
#include "experiment/plan/disk.hpp"
#include "tests/in_process.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {

namespace fs = std::filesystem;

std::shared_ptr<spdlog::logger> quiet(const std::string& name) {
  return std::make_shared<spdlog::logger>(name, std::make_shared<spdlog::sinks::null_sink_mt>());
}

void writeSample(const std::string& path, std::int64_t n) {
  SnapshotWriter w(path);
  w.section("sample");
  w.i64(n);
  w.f64(0.25);
  w.str("eye");
  w.blob({1, 2, 3});
  w.doubles(std::vector<double>{1.5, -2.5});
  w.commit();
}

std::int64_t readSample(const std::string& path) {
  SnapshotReader r(path, 1 << 20);
  r.section("sample");
  const std::int64_t n = r.i64("n");
  EXPECT_EQ(r.f64("x"), 0.25);
  EXPECT_EQ(r.str("name", 64), "eye");
  EXPECT_EQ(r.blob("bytes", 16), (std::vector<std::uint8_t>{1, 2, 3}));
  std::vector<double> d;
  r.doubles("weights", d, 2);
  EXPECT_EQ(d, (std::vector<double>{1.5, -2.5}));
  r.end();
  return n;
}

std::string refusal(const std::function<void()>& f) {
  try {
    f();
  } catch (const SnapshotError& e) {
    return e.what();
  }
  return "";
}

TEST(Snapshot, WhatIsWrittenIsReadBackAndNoTemporaryFileStays) {
  const std::string path = test::tempDir("snapshot-roundtrip") + "/run/eye.snapshot";
  writeSample(path, 42);
  EXPECT_EQ(readSample(path), 42);
  EXPECT_FALSE(fs::exists(path + ".tmp"));
}

TEST(Snapshot, ADamagedCutOrForeignFileIsRefusedNamingIt) {
  const std::string dir = test::tempDir("snapshot-damaged");
  const std::string path = dir + "/eye.snapshot";
  writeSample(path, 7);
  std::string bytes = test::slurp(path);

  std::string flipped = bytes;
  flipped[40] ^= 0x10;
  std::ofstream(dir + "/flipped", std::ios::binary) << flipped;
  EXPECT_NE(refusal([&] { readSample(dir + "/flipped"); }).find("checksum: does not match"), std::string::npos);

  std::ofstream(dir + "/cut", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  EXPECT_NE(refusal([&] { readSample(dir + "/cut"); }).find("snapshot " + dir + "/cut"), std::string::npos);

  std::ofstream(dir + "/other", std::ios::binary) << std::string(100, 'x');
  EXPECT_NE(refusal([&] { readSample(dir + "/other"); }).find("checksum"), std::string::npos);

  EXPECT_NE(refusal([&] { SnapshotReader r(path, 16); }).find("more than the 16"), std::string::npos);

  // Read in another order than written: the section is named.
  const std::string why = refusal([&] {
    SnapshotReader r(path, 1 << 20);
    r.section("eye");
  });
  EXPECT_NE(why.find("[eye]: expected here, found '[sample]'"), std::string::npos) << why;
  // A count beyond its bound or the bytes left is refused before anything is allocated.
  const std::string big = refusal([&] {
    SnapshotReader r(path, 1 << 20);
    r.section("sample");
    r.within("n", 0, 3);
  });
  EXPECT_NE(big.find("n: 7 is outside [0, 3]"), std::string::npos) << big;
}

TEST(Snapshot, ASnapshotSaysTheReleaseThatWroteItAndOneOf010WhichDidNotStillReads) {
  const std::string dir = test::tempDir("snapshot-release");
  writeSample(dir + "/now.snapshot", 5);
  EXPECT_EQ(SnapshotReader(dir + "/now.snapshot", 1 << 20).writtenBy(), affordVersion());
  // As 0.1.0 wrote it (format 1): the magic, the format, the fields, their FNV-1a 64.
  const std::string now = test::slurp(dir + "/now.snapshot");
  const std::size_t head = 16, named = 8 + std::string(affordVersion()).size();
  std::string old = now.substr(0, head + 8) + now.substr(head + 8 + named, now.size() - 8 - head - 8 - named);
  const std::int64_t one = 1;
  old.replace(head, 8, reinterpret_cast<const char*>(&one), 8);
  const std::uint64_t sum = fnv1a64(old.data(), old.size());
  old.append(reinterpret_cast<const char*>(&sum), 8);
  std::ofstream(dir + "/old.snapshot", std::ios::binary) << old;
  EXPECT_EQ(readSample(dir + "/old.snapshot"), 5);
  EXPECT_EQ(SnapshotReader(dir + "/old.snapshot", 1 << 20).writtenBy(), "0.1.0 or earlier");
  // One of a later format than this build reads is refused, saying so.
  std::string later = old;
  const std::int64_t nine = 9;
  later.replace(head, 8, reinterpret_cast<const char*>(&nine), 8);
  const std::uint64_t later_sum = fnv1a64(later.data(), later.size() - 8);
  later.replace(later.size() - 8, 8, reinterpret_cast<const char*>(&later_sum), 8);
  std::ofstream(dir + "/later.snapshot", std::ios::binary) << later;
  const std::string why = refusal([&] { SnapshotReader r(dir + "/later.snapshot", 1 << 20); });
  EXPECT_NE(why.find("version: format 9, this build reads formats 1 to"), std::string::npos) << why;
}

// A process killed with SIGKILL in the middle of writing its next snapshot:
// the earlier one is still there, whole.
TEST(Snapshot, AWriterKilledWhileItWritesLeavesTheEarlierSnapshotWhole) {
  const std::string path = test::tempDir("snapshot-killed") + "/predictors.snapshot";
  writeSample(path, 1);
  int ready[2];
  ASSERT_EQ(pipe(ready), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    SnapshotWriter w(path);
    w.section("sample");
    const std::vector<std::uint8_t> chunk(1 << 16, 0xab);
    w.blob(chunk);
    char c = 1;
    if (write(ready[1], &c, 1) != 1) _exit(2);
    for (;;) w.blob(chunk);  // until killed
  }
  char c = 0;
  ASSERT_EQ(read(ready[0], &c, 1), 1);  // it is writing
  kill(child, SIGKILL);
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_TRUE(fs::exists(path + ".tmp"));  // what it was writing, never put in place
  EXPECT_EQ(readSample(path), 1);
  writeSample(path, 2);  // the next one replaces the temporary file and the earlier snapshot
  EXPECT_EQ(readSample(path), 2);
  close(ready[0]);
  close(ready[1]);
}

// A snapshot written by a forked copy of the process: the file is in place
// once the copy has ended; a copy that fails says why, and the earlier
// snapshot stays.
TEST(Snapshot, AForkedCopyPutsItInPlaceOrSaysWhyItFailed) {
  const std::string path = test::tempDir("snapshot-forked") + "/eye.snapshot";
  writeSample(path, 1);
  {
    SnapshotChild copy([&] { writeSample(path, 2); });
    EXPECT_GT(copy.pid(), 0);
    EXPECT_TRUE(copy.ended(/*wait=*/true));
    EXPECT_EQ(copy.error(), "");
  }
  EXPECT_EQ(readSample(path), 2);
  SnapshotChild failed([&] {
    SnapshotWriter w(path);
    w.section("sample");
    throw SnapshotError("snapshot " + path + ".tmp: write failed (No space left on device)");
  });
  ASSERT_TRUE(failed.ended(/*wait=*/true));
  EXPECT_EQ(failed.error(), "snapshot " + path + ".tmp: write failed (No space left on device)");
  EXPECT_FALSE(fs::exists(path + ".tmp"));  // the copy's writer removed what it had begun
  EXPECT_EQ(readSample(path), 2);
}

// The process killed (SIGKILL) while its forked copy writes the next
// snapshot: the copy dies with it, and the earlier snapshot is whole.
TEST(Snapshot, AForkedCopyDiesWithItsProcessAndTheEarlierSnapshotStaysWhole) {
  const std::string path = test::tempDir("snapshot-forked-killed") + "/predictors.snapshot";
  writeSample(path, 1);
  // Orphans come to this test, so it sees the copy end.
  ASSERT_EQ(prctl(PR_SET_CHILD_SUBREAPER, 1), 0);
  int ready[2];
  ASSERT_EQ(pipe(ready), 0);
  const pid_t process = fork();
  ASSERT_GE(process, 0);
  if (process == 0) {
    SnapshotChild copy([&] {
      SnapshotWriter w(path);
      w.section("sample");
      const std::vector<std::uint8_t> chunk(1 << 16, 0xab);
      w.blob(chunk);
      const pid_t me = getpid();
      if (write(ready[1], &me, sizeof me) != sizeof me) _exit(2);
      for (;;) w.blob(chunk);  // until it dies
    });
    copy.ended(/*wait=*/true);
    _exit(0);
  }
  pid_t copy = 0;
  ASSERT_EQ(read(ready[0], &copy, sizeof copy), static_cast<ssize_t>(sizeof copy));  // the copy is writing
  kill(process, SIGKILL);
  int status = 0;
  ASSERT_EQ(waitpid(process, &status, 0), process);
  // The copy, now this test's child, ends by SIGKILL (it would write forever otherwise).
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  pid_t ended = 0;
  while ((ended = waitpid(copy, &status, WNOHANG)) == 0 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  if (ended != copy) kill(copy, SIGKILL);
  ASSERT_EQ(ended, copy) << "the copy outlived its process";
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
  prctl(PR_SET_CHILD_SUBREAPER, 0);
  EXPECT_EQ(readSample(path), 1);
  close(ready[0]);
  close(ready[1]);
}

process_status_t readerStatus(const std::string& run, const std::string& process,
                              const std::vector<std::pair<std::string, std::int64_t>>& takes) {
  process_status_t st{};
  st.run_id = run;
  st.process = process;
  st.pid = 1;
  st.state = process_status_t::RUNNING;
  st.config_digest = st.counts_config = 0;  // the request joined
  st.n_channels = 0;
  for (const auto& [channel, from] : takes) {
    st.takes.push_back(channel);
    st.takes_from.push_back(from);
  }
  st.n_takes = static_cast<int32_t>(st.takes.size());
  st.started = 0;
  st.n_copies = 0;
  return st;
}

struct Outbound : ::testing::Test {
  std::vector<std::int64_t> republished;
  EdgeOutbound out{quiet("environment"), [this](const std::string&, const std::vector<std::uint8_t>& b) {
                     republished.push_back(b.front());
                   }};
  RecoveryConfig recovery{/*snapshot_steps=*/100, /*history_keep=*/3, /*history_mb=*/64, /*snapshot_mb=*/64};
  ProtocolConfig protocol = test::shippedProtocol();

  void publish(int n, std::size_t bytes = 16) {
    for (int i = 0; i < n; ++i) {
      const std::int64_t serial = out.nextSerial("SCENE");
      std::vector<std::uint8_t> m(bytes, 0);
      m.front() = static_cast<std::uint8_t>(serial);
      out.kept("SCENE", serial + 1000, std::move(m));
    }
  }
  std::int64_t heldFrom() const { return out.counts().at(0).held_from; }
  std::vector<std::int64_t> ask(std::int64_t first, std::int64_t last) {
    republished.clear();
    resend_t r;
    r.run_id = "run-1";
    r.channel = "SCENE";
    r.first = first;
    r.last = last;
    r.requester = "eye";
    r.config_digest = 0;
    out.answer(r, protocol);
    return republished;
  }
};

TEST_F(Outbound, APublisherLetsGoOnlyOfWhatEveryReaderOfTheRunHasASnapshotAfter) {
  out.join("run-1", {}, recovery, {"eye", "predictors", "motivation"});
  publish(10);
  EXPECT_EQ(heldFrom(), 0);
  out.readerSaid(readerStatus("run-1", "eye", {{"SCENE", 6}, {"DECISION", 4}}));
  out.readerSaid(readerStatus("run-1", "predictors", {{"FOCUS", 9}}));  // does not take SCENE
  EXPECT_EQ(heldFrom(), 0) << "the motivation, not heard yet, may take SCENE";
  out.readerSaid(readerStatus("other-run", "motivation", {}));
  EXPECT_EQ(heldFrom(), 0) << "a STATUS of another run says nothing of this one";
  out.readerSaid(readerStatus("run-1", "motivation", {{"PREDICTION", 9}}));
  EXPECT_EQ(heldFrom(), 6);
  EXPECT_EQ(ask(2, 8), (std::vector<std::int64_t>{6, 7, 8})) << "what was let go is not republished";
  out.readerSaid(readerStatus("run-1", "eye", {{"SCENE", 10}}));
  EXPECT_EQ(heldFrom(), 7) << "the last history_keep (3) messages stay whatever readers say";
  EXPECT_EQ(out.nextSerial("SCENE"), 10);
  EXPECT_EQ(out.lastDigest("SCENE"), 1009);
}

TEST_F(Outbound, WithoutSnapshotsOrBeforeEveryReaderIsHeardEverythingIsHeld) {
  recovery.snapshot_steps = 0;
  out.join("run-1", {}, recovery, {"eye"});
  publish(10);
  out.readerSaid(readerStatus("run-1", "eye", {{"SCENE", 8}}));
  EXPECT_EQ(heldFrom(), 0);
  EXPECT_EQ(ask(0, 9).size(), 10u);
}

TEST_F(Outbound, WhatIsHeldStaysUnderHistoryMbWhateverReadersSay) {
  recovery.history_mb = 1;
  out.join("run-1", {}, recovery, {"eye"});
  publish(20, 300 * 1024);  // 6 MB published, nobody heard
  EXPECT_LE(out.heldBytes(), std::size_t{1} << 20);
  EXPECT_EQ(heldFrom(), 17);
  EXPECT_EQ(out.letGoOverBound(), 17);
  EXPECT_EQ(out.nextSerial("SCENE"), 20);
}

TEST_F(Outbound, ASnapshotOfWhatWasPublishedIsReadBackWhole) {
  out.join("run-1", {}, recovery, {"eye"});
  publish(10);
  out.readerSaid(readerStatus("run-1", "eye", {{"SCENE", 5}}));
  const std::string path = test::tempDir("snapshot-outbound") + "/environment.snapshot";
  {
    SnapshotWriter w(path);
    out.save(w);
    w.commit();
  }
  EdgeOutbound back(quiet("environment"), [](const std::string&, const std::vector<std::uint8_t>&) {});
  back.join("run-1", {}, recovery, {"eye"});
  SnapshotReader r(path, 1 << 20);
  back.load(r, 1 << 20);
  r.end();
  EXPECT_EQ(back.nextSerial("SCENE"), 10);
  EXPECT_EQ(back.lastDigest("SCENE"), 1009);
  EXPECT_EQ(back.counts().at(0).held_from, 5);
}

// A receiver behind what its publisher still holds (restarted without its
// snapshot, on another host) cannot catch up: the run fails naming the channel.
TEST(Snapshot, AReceiverNeedingWhatWasLetGoFailsTheRunNamingTheChannel) {
  lcm::LCM lcm{"memq://"};
  RunConfig config = test::shippedConfig();
  Edge eye{lcm, quiet("eye"), "eye", config.protocol};
  eye.join("run-1", &config, {});
  eye.subscribe(ch::decision, [](const decision_t&) { return Turn::take(); }, Scope::Run, Order::Serial);
  std::string failure;
  eye.onFailure([&](const std::string& channel, const std::string& why) { failure = channel + ": " + why; });
  process_status_t st{};
  st.run_id = st.counts_run = "run-1";
  st.config_digest = st.counts_config = 0;
  st.process = "motivation";
  st.pid = 7;
  st.state = process_status_t::RUNNING;
  st.channels = {ch::decision.name};
  st.counts = {5000};
  st.held_from = {4000};
  st.n_channels = 1;
  st.n_takes = 0;
  st.started = 0;
  st.n_copies = 0;
  eye.claim(st);
  EXPECT_TRUE(eye.failed());
  EXPECT_NE(failure.find("DECISION: serials 0..3999 are no longer held by its publisher (motivation holds it from "
                         "serial 4000)"),
            std::string::npos)
      << failure;
}

// What `afford experiment` says a run will write: at least what the run's
// messages take in its log, and not wildly more (an action at every step; for
// the goals agent, its planner's most looks, goals and forward queries a step).
struct DiskCase {
  const char* experiment;
  System system;
  int most_times;  // the estimate at most this many times what the run wrote
};
class Disk : public ::testing::TestWithParam<DiskCase> {};

TEST_P(Disk, TheEstimateBoundsWhatARunWritesToItsLog) {
  const DiskCase& c = GetParam();
  const std::int64_t steps = 300;
  PlannedRun run;
  run.spec.run_id = "test-run";
  run.spec.steps = steps;
  run.spec.config_yaml = test::shippedConfigYaml(c.experiment, c.system, 3, steps);
  run.keep_log = true;
  const DiskNeed need = diskNeed({run}, 1);
  EXPECT_EQ(need.kept_logs, 1u);
  EXPECT_EQ(need.snapshots, 0u) << "a run shorter than snapshot_steps takes none";
  test::InProcessRun live(run.spec.config_yaml, c.system, 3, steps);
  ASSERT_TRUE(live.outcome.ok) << live.outcome.error;
  std::uint64_t logged = 0;  // the run channels' events, as the logger writes them
  for (const auto& e : live.events)
    if (isSerialChannel(e.channel)) logged += 4 + 8 + 8 + 4 + 4 + e.channel.size() + e.data.size();
  EXPECT_GE(need.logs, logged);
  EXPECT_LE(need.logs, static_cast<std::uint64_t>(c.most_times) * logged);
  EXPECT_NE(diskLine(need).find("of logs (1 kept"), std::string::npos) << diskLine(need);
  EXPECT_NE(diskWarning(need, need.total() / 2, "logs").find("has "), std::string::npos);
  EXPECT_EQ(diskWarning(need, need.total(), "logs"), "");
}

INSTANTIATE_TEST_SUITE_P(Systems, Disk,
                         ::testing::Values(DiskCase{"base", System::IMP, 3}, DiskCase{"goals", System::GOALS, 3},
                                           DiskCase{"goals-multi-step", System::GOALS, 5}),
                         [](const ::testing::TestParamInfo<DiskCase>& i) {
                           std::string name = std::string(i.param.experiment) + "_" + (i.param.system == System::GOALS ? "GOALS" : "IMP");
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });

}  // namespace
}  // namespace afford
