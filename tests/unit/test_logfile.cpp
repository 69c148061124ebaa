// The project's log reader and writer (afford/logfile.hpp): what the writer
// writes, the reader and LCM's own reader read back alike; every malformed
// part of a file is skipped and named with its offset, with no allocation
// beyond the caps; an event cut short at the end is torn, not malformed.
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "afford/logfile.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;

Bytes pattern(std::size_t n, std::uint8_t seed) {
  Bytes b(n);
  for (std::size_t i = 0; i < n; ++i) b[i] = static_cast<std::uint8_t>(seed * 31 + i);
  return b;
}
Bytes fileBytes(const fs::path& f) {
  std::ifstream in(f, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), {});
}
void writeBytes(const fs::path& f, const Bytes& b) {
  std::ofstream(f, std::ios::binary).write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
}
// An event as LCM lays it out, with the lengths given (which may lie; kTrue: the true ones).
constexpr std::int64_t kTrue = INT64_MIN;
Bytes event(const std::string& channel, const Bytes& data, std::int64_t channel_len = kTrue, std::int64_t data_len = kTrue) {
  Bytes b;
  auto put = [&](std::uint64_t v, int n) {
    for (int i = n - 1; i >= 0; --i) b.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  };
  put(0xEDA1DA01u, 4);
  put(7, 8);
  put(123456, 8);
  put(static_cast<std::uint32_t>(channel_len == kTrue ? static_cast<std::int64_t>(channel.size()) : channel_len), 4);
  put(static_cast<std::uint32_t>(data_len == kTrue ? static_cast<std::int64_t>(data.size()) : data_len), 4);
  b.insert(b.end(), channel.begin(), channel.end());
  b.insert(b.end(), data.begin(), data.end());
  return b;
}

class LogFileTest : public ::testing::Test {
 protected:
  fs::path dir_ = test::tempDir("logfile");
  LogLimits limits_;  // 63-byte channels, 1 MB events
};

TEST_F(LogFileTest, WhatTheWriterWritesBothReadersReadBack) {
  const fs::path f = dir_ / "log.00.lcm";
  {
    LogWriter w(f);
    w.write("SCENE", pattern(14000, 1).data(), 14000, 100);
    w.write("FOCUS", pattern(1323, 2).data(), 1323, 200);
    w.write("EMPTY", nullptr, 0, 300);
    w.close();
  }
  const LogFileContents c = readLogFile(f, limits_);
  ASSERT_EQ(c.events.size(), 3u);
  EXPECT_EQ(c.events[0].channel, "SCENE");
  EXPECT_EQ(c.events[0].data, pattern(14000, 1));
  EXPECT_EQ(c.events[0].utime, 100);
  EXPECT_EQ(c.events[0].offset, 0);
  EXPECT_EQ(c.events[1].offset, 28 + 5 + 14000);
  EXPECT_TRUE(c.events[2].data.empty());
  EXPECT_EQ(c.problem_count, 0);
  EXPECT_EQ(c.torn_bytes, 0);
  // LCM's own reader (the one lcm-logplayer uses) reads the same events.
  lcm::LogFile lcm_log(f.string(), "r");
  int n = 0;
  while (const lcm::LogEvent* e = lcm_log.readNextEvent()) {
    EXPECT_EQ(e->channel, c.events[static_cast<std::size_t>(n)].channel);
    EXPECT_EQ(e->datalen, static_cast<std::int32_t>(c.events[static_cast<std::size_t>(n)].data.size()));
    EXPECT_EQ(e->eventnum, n);
    ++n;
  }
  EXPECT_EQ(n, 3);
}

TEST_F(LogFileTest, TheWriterNeverOverwritesAFile) {
  const fs::path f = dir_ / "kept.lcm";
  writeBytes(f, {1, 2, 3});
  EXPECT_THROW(LogWriter w(f), std::runtime_error);
  EXPECT_EQ(fileBytes(f), (Bytes{1, 2, 3}));
}

TEST_F(LogFileTest, ALengthBeyondTheCapIsSkippedAtItsOffsetWithoutAllocatingIt) {
  Bytes b = event("A", pattern(10, 3));
  const auto bad_at = static_cast<std::int64_t>(b.size());
  const Bytes huge = event("SCENE", pattern(3000, 4), kTrue, 0x7FFFFFFF);  // the 3 KB file of the report
  b.insert(b.end(), huge.begin(), huge.end());
  const Bytes after = event("B", pattern(20, 5));
  b.insert(b.end(), after.begin(), after.end());
  writeBytes(dir_ / "huge.lcm", b);
  const LogFileContents c = readLogFile(dir_ / "huge.lcm", limits_);
  ASSERT_EQ(c.events.size(), 2u);
  EXPECT_EQ(c.events[0].channel, "A");
  EXPECT_EQ(c.events[1].channel, "B");
  EXPECT_EQ(c.events[1].data, pattern(20, 5));
  ASSERT_EQ(c.problem_count, 1);
  EXPECT_EQ(c.problems[0].offset, bad_at);
  EXPECT_NE(c.problems[0].what.find("data length 2147483647"), std::string::npos) << c.problems[0].what;
}

TEST_F(LogFileTest, EveryKindOfMalformedPartIsSkippedAndNamed) {
  Bytes b = event("OK1", pattern(5, 6));
  const std::int64_t junk_at = static_cast<std::int64_t>(b.size());
  for (int i = 0; i < 50; ++i) b.push_back(static_cast<std::uint8_t>(i));  // no sync word
  const std::int64_t channel_at = static_cast<std::int64_t>(b.size());
  const Bytes zero_channel = event("", pattern(4, 7));
  b.insert(b.end(), zero_channel.begin(), zero_channel.end());
  const std::int64_t long_at = static_cast<std::int64_t>(b.size());
  const Bytes long_channel = event(std::string(64, 'C'), pattern(4, 8));
  b.insert(b.end(), long_channel.begin(), long_channel.end());
  const std::int64_t negative_at = static_cast<std::int64_t>(b.size());
  const Bytes negative = event("N", pattern(4, 9), kTrue, -5);
  b.insert(b.end(), negative.begin(), negative.end());
  const std::int64_t control_at = static_cast<std::int64_t>(b.size());
  const Bytes control = event("X\x1b[2J", pattern(4, 10));
  b.insert(b.end(), control.begin(), control.end());
  const Bytes ok2 = event("OK2", pattern(6, 11));
  b.insert(b.end(), ok2.begin(), ok2.end());
  writeBytes(dir_ / "mixed.lcm", b);
  const LogFileContents c = readLogFile(dir_ / "mixed.lcm", limits_);
  ASSERT_EQ(c.events.size(), 2u);
  EXPECT_EQ(c.events[0].channel, "OK1");
  EXPECT_EQ(c.events[1].channel, "OK2");
  ASSERT_EQ(c.problem_count, 5);
  const std::vector<std::int64_t> offsets{junk_at, channel_at, long_at, negative_at, control_at};
  for (std::size_t i = 0; i < offsets.size(); ++i) EXPECT_EQ(c.problems[i].offset, offsets[i]) << c.problems[i].what;
  EXPECT_NE(c.problems[1].what.find("channel length 0"), std::string::npos);
  EXPECT_NE(c.problems[4].what.find("printable"), std::string::npos);
}

TEST_F(LogFileTest, AnEventCutShortAtTheEndIsTorn) {
  Bytes b = event("OK", pattern(100, 12));
  const Bytes last = event("CUT", pattern(500, 13));
  b.insert(b.end(), last.begin(), last.end() - 200);
  writeBytes(dir_ / "torn.lcm", b);
  const LogFileContents c = readLogFile(dir_ / "torn.lcm", limits_);
  ASSERT_EQ(c.events.size(), 1u);
  EXPECT_EQ(c.torn_bytes, static_cast<std::int64_t>(last.size() - 200));
  EXPECT_EQ(c.problem_count, 0);
}

TEST_F(LogFileTest, ATornEventWhoseDataHoldsASyncWordIsStillTorn) {
  Bytes data = pattern(400, 14);
  const Bytes sync = {0xED, 0xA1, 0xDA, 0x01};
  std::copy(sync.begin(), sync.end(), data.begin() + 100);  // a sync word inside the data, with no event after it
  Bytes b = event("OK", pattern(50, 15));
  const Bytes last = event("CUT", data);
  b.insert(b.end(), last.begin(), last.end() - 150);
  writeBytes(dir_ / "torn-sync.lcm", b);
  const LogFileContents c = readLogFile(dir_ / "torn-sync.lcm", limits_);
  ASSERT_EQ(c.events.size(), 1u);
  EXPECT_EQ(c.problem_count, 0) << c.problems[0].what;
  EXPECT_EQ(c.torn_bytes, static_cast<std::int64_t>(last.size() - 150));
  // A tail of one to three bytes of a sync word is torn too.
  for (std::size_t n = 1; n <= 3; ++n) {
    Bytes t = event("OK", pattern(50, 15));
    t.insert(t.end(), sync.begin(), sync.begin() + static_cast<std::ptrdiff_t>(n));
    writeBytes(dir_ / "torn-tail.lcm", t);
    const LogFileContents d = readLogFile(dir_ / "torn-tail.lcm", limits_);
    EXPECT_EQ(d.torn_bytes, static_cast<std::int64_t>(n));
    EXPECT_EQ(d.problem_count, 0);
  }
}

// A file of headers that are no events (a bad channel each, a data length near the cap): each is skipped
// and named (the reader looks at the channel before it reads any data).
TEST_F(LogFileTest, EachOfManyHeadersThatAreNoEventsIsSkippedAndNamed) {
  Bytes b;
  const Bytes bad = event("\x01", {}, kTrue, 1 << 20);
  for (int i = 0; i < 2000; ++i) b.insert(b.end(), bad.begin(), bad.end());
  b.resize(b.size() + (1 << 20), 0);
  writeBytes(dir_ / "headers.lcm", b);
  LogReader in(dir_ / "headers.lcm", limits_);
  LogEvent e;
  EXPECT_FALSE(in.next(e));
  EXPECT_EQ(in.problemCount(), 2000);
}

TEST_F(LogFileTest, AFileThatIsNoLogHasNoEventAndOneProblem) {
  writeBytes(dir_ / "text.lcm", Bytes{'n', 'o', 't', ' ', 'a', ' ', 'l', 'o', 'g'});
  const LogFileContents c = readLogFile(dir_ / "text.lcm", limits_);
  EXPECT_TRUE(c.events.empty());
  EXPECT_EQ(c.problem_count, 1);
  EXPECT_EQ(c.problems[0].offset, 0);
  EXPECT_THROW(readLogFile(dir_ / "absent.lcm", limits_), std::runtime_error);
  EXPECT_THROW(readLogFile(dir_, limits_), std::runtime_error);  // a folder
}

}  // namespace
}  // namespace afford
