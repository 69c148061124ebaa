// The runner's watch on the processes of a run that go silent
// (experiment/run/silence.hpp), and what the progress board makes of it: a
// process not heard for a few heartbeats is said at once, once, with the pid
// last heard and where to look; the board shows whom the run waits for, not a
// time left that only grows. The wrong-URL restart this is for, on a live
// group: tests/keys/test_key_hints.sh.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "experiment/execute/progress.hpp"
#include "experiment/run/silence.hpp"
#include "tests/said.hpp"

namespace afford {
namespace {

using std::chrono::milliseconds;

using test::Said;

TEST(Silence, AProcessNotHeardForAFewBeatsIsSaidOnceAtOnceAndSaidBackWhenHeardAgain) {
  Said said;
  Silence silence(said.log, milliseconds(3000));
  std::vector<std::string> waited;
  silence.onWaiting([&](const std::string& who) { waited.push_back(who); });
  const auto t0 = Silence::Clock::now();
  const auto at = [&](int ms) { return t0 + milliseconds(ms); };

  // The runner looks after each message it handles, or every few milliseconds.
  for (int ms = 0; ms <= 2900; ms += 100)
    silence.look("r1", {{"environment", 40, at(ms - ms % 500)}, {"eye", 41, at(0)}}, at(ms));
  EXPECT_EQ(said.text.str(), "");
  EXPECT_TRUE(waited.empty());

  // The eye's last beat was at 0 (killed, and started on another bus): said as the third second passes.
  silence.look("r1", {{"environment", 40, at(3000)}, {"eye", 41, at(0)}}, at(3100));
  EXPECT_EQ(static_cast<int>(said.lines().size()), 1) << said.text.str();
  EXPECT_NE(said.text.str().find("run 'r1': process eye not heard for 3.1 s (pid 41 last)"), std::string::npos)
      << said.text.str();
  EXPECT_NE(said.text.str().find("check its bus URL"), std::string::npos) << said.text.str();
  EXPECT_EQ(waited, std::vector<std::string>{"eye"});

  // Still silent: nothing more (once), however often the runner looks.
  for (int ms = 3200; ms < 30000; ms += 100) silence.look("r1", {{"environment", 40, at(ms)}, {"eye", 41, at(0)}}, at(ms));
  EXPECT_EQ(static_cast<int>(said.lines().size()), 1) << said.text.str();
  EXPECT_EQ(waited, std::vector<std::string>{"eye"});

  // Started again where it should be: heard, said back, and nobody is waited for.
  silence.look("r1", {{"environment", 40, at(30000)}, {"eye", 57, at(30000)}}, at(30000));
  EXPECT_EQ(static_cast<int>(said.lines().size()), 2) << said.text.str();
  EXPECT_NE(said.text.str().find("process eye heard again (pid 57)"), std::string::npos) << said.text.str();
  EXPECT_EQ(waited, (std::vector<std::string>{"eye", ""}));

  // Two at once are both waited for; the run's end waits for none.
  for (int ms = 30100; ms <= 34000; ms += 100)
    silence.look("r1", {{"environment", 40, at(30000)}, {"eye", 57, at(30000)}}, at(ms));
  EXPECT_EQ(waited.back(), "environment, eye");
  silence.reset();
  EXPECT_EQ(waited.back(), "");
}

// A silence the runner did not listen through (a pause of its own, e.g. a long handler in its thread) is no
// process's: it listens afresh, and says only what stays silent while it does.
TEST(Silence, APauseOfTheRunnerItselfIsNotAProcesssSilence) {
  Said said;
  Silence silence(said.log, milliseconds(3000));
  const auto t0 = Silence::Clock::now();
  const auto at = [&](int ms) { return t0 + milliseconds(ms); };
  silence.look("r1", {{"eye", 41, at(0)}}, at(0));
  silence.look("r1", {{"eye", 41, at(0)}}, at(10000));  // ten seconds away: the eye's beats wait in the queue
  EXPECT_EQ(said.text.str(), "");
  silence.look("r1", {{"eye", 41, at(10050)}}, at(10050));  // ... and come
  for (int ms = 10100; ms < 12950; ms += 100) silence.look("r1", {{"eye", 41, at(10050)}}, at(ms));
  EXPECT_EQ(said.text.str(), "");
  // Heard at 10050 and not since, while the runner listened: said once three seconds are over.
  for (int ms = 12950; ms < 13200; ms += 100) silence.look("r1", {{"eye", 41, at(10050)}}, at(ms));
  EXPECT_EQ(said.starting("run 'r1': process eye not heard for 3.0"), 1) << said.text.str();
}

// The board's lines as printed (--progress lines, drawn at every event).
struct Board {
  std::FILE* f = std::tmpfile();
  Progress progress{ProgressOptions{"lines", 0, {}}, "intrinsic runs", 1, {1000}, 0, 1, f};
  ~Board() { std::fclose(f); }
  std::string last() {
    std::fflush(f);
    std::rewind(f);
    std::string line, out;
    for (char buf[512]; std::fgets(buf, sizeof buf, f);) {
      line += buf;
      if (!line.empty() && line.back() == '\n') out = std::exchange(line, "");
    }
    return out;
  }
};

TEST(Progress, ARunWaitingForAProcessShowsWhomItWaitsForNotATimeLeft) {
  Board b;
  b.progress.started(0, "r1", 1000);
  b.progress.step(0, 100);
  EXPECT_NE(b.last().find(" left"), std::string::npos) << b.last();
  b.progress.waiting(0, "eye");
  b.progress.step(0, 101);
  EXPECT_NE(b.last().find("waiting for eye"), std::string::npos) << b.last();
  EXPECT_EQ(b.last().find(" left"), std::string::npos) << "a time left while the run waits: " << b.last();
  b.progress.waiting(0, "");
  b.progress.step(0, 102);
  EXPECT_EQ(b.last().find("waiting for"), std::string::npos) << b.last();
  EXPECT_NE(b.last().find(" left"), std::string::npos) << b.last();
}

TEST(Progress, LinesGivenAFunctionGoToItAndNotToTheFile) {
  // afford.run gives its lines to Python (a notebook shows sys.stderr, not the process's own).
  std::vector<std::string> said;
  std::FILE* f = std::tmpfile();
  {
    Progress p{ProgressOptions{"auto", 0, [&said](const std::string& line) { said.push_back(line); }},
               "intrinsic runs", 1, {1000}, 0, 1, f};
    p.started(0, "r1", 1000);
    p.step(0, 100);
  }
  ASSERT_FALSE(said.empty());
  EXPECT_EQ(said.back().rfind("progress: ", 0), 0u) << said.back();
  EXPECT_NE(said.back().find("r1"), std::string::npos) << said.back();
  EXPECT_EQ(std::ftell(f), 0) << "written to the file too";
  std::fclose(f);
}

}  // namespace
}  // namespace afford
