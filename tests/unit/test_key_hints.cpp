// A reader whose key, or lack of one, does not fit the bus (afford/auth.hpp,
// KeyMismatch): a tagged message is told by its structure (its digest sits
// the trailer's length before its end, afford/seal.hpp), not by what a decoder
// made of it; a flood of them is one line naming the fix, then counts, never a
// line a message. The same for recordings: a keyed bus's recording read
// without its key (afford replay, explain, watch --log, the Python package's
// read_log) says so, once, and its refusal names the fix.
#include <gtest/gtest.h>
#include <string>
#include <vector>

#include "afford/edge.hpp"
#include "afford/logfile.hpp"
#include "afford/process_status_t.hpp"
#include "afford/run_config_t.hpp"
#include "experiment/replay/replay.hpp"
#include "tests/said.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {

using test::Said;

constexpr const char* kTaggedHint = "tagged messages heard: this bus is keyed; give --bus-key";
constexpr const char* kUntaggedHint = "untagged messages heard: this bus is not keyed (or its publishers lack the key)";
constexpr const char* kOtherKeyHint = "messages tagged with another key heard";

process_status_t statusOf(const std::string& process, int pid, std::int64_t beat) {
  process_status_t st{};
  st.step = -1;
  st.process = process;
  st.pid = pid;
  st.beat = beat;
  st.state = process_status_t::WAITING;
  st.config_digest = 0;
  st.counts_config = 0;
  st.n_channels = 0;
  st.n_takes = 0;
  return st;
}

struct KeyHints : ::testing::Test {
  std::string dir = test::tempDir("key-hints");
  std::shared_ptr<const BusKey> newKey(const std::string& name) {
    BusKey::writeNew(dir + "/" + name);
    return std::make_shared<const BusKey>(BusKey::fromFile(dir + "/" + name));
  }
};

TEST_F(KeyHints, ATagIsToldByWhereTheDigestIsNotByADecoder) {
  const auto key = newKey("bus.key"), other = newKey("other.key");
  process_status_t st = statusOf("eye", 7, 1);
  const std::vector<std::uint8_t> plain = sealed(st);
  const std::vector<std::uint8_t> tagged = key->tagged(ch::status.name, plain.data(), plain.size(), {1, 0, 0});
  EXPECT_EQ(sealAt(plain.data(), plain.size(), BusKey::kTrailerBytes), SealAt::End);
  EXPECT_EQ(sealAt(tagged.data(), tagged.size(), BusKey::kTrailerBytes), SealAt::BeforeTrailer);

  EXPECT_EQ(keyMismatchOf(nullptr, plain.data(), plain.size()), KeyMismatch::None);  // fits: no key, no tag
  EXPECT_EQ(keyMismatchOf(nullptr, tagged.data(), tagged.size()), KeyMismatch::TaggedWithoutKey);
  EXPECT_EQ(keyMismatchOf(key.get(), plain.data(), plain.size()), KeyMismatch::UntaggedWithKey);
  ASSERT_FALSE(other->verify(ch::status.name, tagged.data(), tagged.size()));
  EXPECT_EQ(keyMismatchOf(other.get(), tagged.data(), tagged.size()), KeyMismatch::OtherKey);

  // Anything else is no message of ours, whatever its length: a byte of the message changed, a trailer of
  // another length, bytes that are no message.
  std::vector<std::uint8_t> damaged = tagged;
  damaged[20] ^= 1;
  EXPECT_EQ(keyMismatchOf(nullptr, damaged.data(), damaged.size()), KeyMismatch::None);
  EXPECT_EQ(keyMismatchOf(key.get(), damaged.data(), damaged.size()), KeyMismatch::None);
  std::vector<std::uint8_t> longer = tagged;
  longer.push_back(0);
  EXPECT_EQ(keyMismatchOf(nullptr, longer.data(), longer.size()), KeyMismatch::None);
  const std::vector<std::uint8_t> noise(tagged.size(), 0xA5);
  EXPECT_EQ(keyMismatchOf(nullptr, noise.data(), noise.size()), KeyMismatch::None);
  EXPECT_EQ(keyMismatchOf(key.get(), noise.data(), 10), KeyMismatch::None);
  EXPECT_EQ(keyMismatchOf(nullptr, noise.data(), 0), KeyMismatch::None);
}

// A reader on a bus whose key it does not have (or has and the bus does not): 600 STATUS beats heard (the
// processes of a group for a minute) are one line naming the fix, and every one of them is counted after it.
struct HeardWithoutTheKey : KeyHints {
  lcm::LCM lcm{"memq://"};
  ProtocolConfig protocol = test::shippedProtocol();
  Said said;
  EdgeDrops drops;

  // `sender_key` speaks 600 STATUS; a reader with `reader_key` listens, then ends (its last summary said).
  void hear(std::shared_ptr<const BusKey> sender_key, std::shared_ptr<const BusKey> reader_key) {
    Edge sender{lcm, said.log, "eye", protocol};
    sender.useKey(std::move(sender_key));
    int taken = 0;
    {
      Edge reader{lcm, said.log, "runner", protocol};
      reader.useKey(std::move(reader_key));
      reader.subscribe(ch::status,
          [&](const process_status_t&) {
            ++taken;
            return Turn::take();
          },
          Scope::Any, Order::None);
      for (int beat = 1; beat <= 600; ++beat) {
        process_status_t st = statusOf("eye", 100 + beat % 6, beat);
        sender.send(ch::status, st);
        while (lcm.handleTimeout(0) > 0) {
        }
      }
      drops = reader.drops();
    }
    EXPECT_EQ(taken, 0);
  }
  void oneLineThenCounts(const std::string& hint) {
    EXPECT_EQ(said.starting(hint), 1) << said.text.str();
    EXPECT_EQ(said.count("dropped message"), 0) << "a line a message: " << said.text.str();
    EXPECT_EQ(said.count("trailing bytes"), 0) << said.text.str();
    for (const auto& line : said.lines())
      EXPECT_TRUE(line.find(hint) == 0 || line.rfind("dropped ", 0) == 0) << "neither the hint nor a count: " << line;
    EXPECT_LE(said.lines().size(), 12u) << said.text.str();
    EXPECT_EQ(said.summarised(), 599) << said.text.str();  // every one after the first, counted
  }
};

TEST_F(HeardWithoutTheKey, AKeyedBusHeardWithoutTheKeyIsOneLineNamingTheFixThenCounts) {
  hear(newKey("bus.key"), nullptr);
  oneLineThenCounts(kTaggedHint);
  EXPECT_EQ(drops.key.tagged, 600);
  EXPECT_EQ(drops.key.said().find(kTaggedHint), 0u) << drops.key.said();
  EXPECT_NE(drops.key.said().find("(600 such messages dropped)"), std::string::npos) << drops.key.said();
}

TEST_F(HeardWithoutTheKey, AnUnkeyedBusHeardWithAKeyIsOneLineNamingTheFixThenCounts) {
  hear(nullptr, newKey("bus.key"));
  oneLineThenCounts(kUntaggedHint);
  EXPECT_EQ(drops.key.untagged, 600);
  EXPECT_EQ(drops.untagged, 600);  // (still counted as without a valid tag, as a process's last line says)
}

TEST_F(HeardWithoutTheKey, ABusHeardWithAnotherKeyIsOneLineNamingTheFixThenCounts) {
  hear(newKey("bus.key"), newKey("mine.key"));
  oneLineThenCounts(kOtherKeyHint);
  EXPECT_EQ(drops.key.other_key, 600);
}

// ---- recordings -------------------------------------------------------------------------------------------

// A recording of a keyed bus as lcm-logger makes it (every message with its stamp and tag): a run's
// RUN_CONFIG and 200 STATUS beats; or the same untagged.
struct Recording : KeyHints {
  std::string file;
  void record(const std::shared_ptr<const BusKey>& key) {
    file = dir + "/recording.lcm";
    LogWriter w(file);
    const auto put = [&](const std::string& channel, const std::vector<std::uint8_t>& plain) {
      const std::vector<std::uint8_t> b =
          key ? key->tagged(channel, plain.data(), plain.size(), {1, static_cast<std::uint64_t>(w.events()), 0}) : plain;
      w.write(channel, b.data(), b.size(), w.events());
    };
    run_config_t rc;
    rc.run_id = "keyed-run";
    rc.step = 0;
    rc.request = 1;
    rc.seed = 1;
    rc.experiment = "base";
    rc.system = "IMP";
    rc.config_yaml = test::shippedConfigYaml("base", System::IMP, 1, 100);
    put(ch::runConfig.name, sealed(rc));
    for (int beat = 1; beat <= 200; ++beat) {
      process_status_t st = statusOf("eye", 9, beat);
      put(ch::status.name, sealed(st));
    }
  }
  // Every event read through the log reader with `key`, the run chosen; the refusal, if any.
  std::string read(const std::shared_ptr<const BusKey>& key, Said& said, RecordedLog* counts = nullptr) {
    RecordedLogStream in(file, *said.log, key.get());
    RunSelector select("", file, *said.log);
    LogEvent e;
    while (in.next(e)) select.take(e);
    if (counts) *counts = in.counts();
    try {
      select.check();
    } catch (const std::exception& ex) {
      return ex.what();
    }
    return "";
  }
};

TEST_F(Recording, AKeyedBusRecordingReadWithoutTheKeyIsRefusedNamingTheFix) {
  record(newKey("bus.key"));
  Said said;
  const std::string refusal = read(nullptr, said);
  EXPECT_NE(refusal.find("no RUN_CONFIG that the edge accepts"), std::string::npos) << refusal;
  EXPECT_NE(refusal.find(kTaggedHint), std::string::npos) << refusal;
  EXPECT_EQ(said.count(kTaggedHint), 1) << said.text.str();
  EXPECT_EQ(said.count("trailing bytes"), 0) << said.text.str();
}

TEST_F(Recording, WithTheKeyItReadsAndWithAnotherOneLineNamesTheFix) {
  const auto key = newKey("bus.key");
  record(key);
  Said right;
  EXPECT_EQ(read(key, right), "");
  EXPECT_EQ(right.text.str(), "");
  Said wrong;
  RecordedLog counts;
  const std::string refusal = read(newKey("other.key"), wrong, &counts);
  EXPECT_NE(refusal.find("no RUN_CONFIG"), std::string::npos) << refusal;
  EXPECT_EQ(wrong.count(kOtherKeyHint), 1) << wrong.text.str();
  EXPECT_EQ(wrong.lines().size(), 1u) << wrong.text.str();  // 201 events skipped: one line, then the count
  EXPECT_EQ(counts.untagged, 201);
  EXPECT_EQ(counts.key.other_key, 201);
}

TEST_F(Recording, AnUnkeyedRecordingReadWithAKeyIsOneLineNamingTheFix) {
  record(nullptr);
  Said said;
  RecordedLog counts;
  read(newKey("bus.key"), said, &counts);
  EXPECT_EQ(said.count(kUntaggedHint), 1) << said.text.str();
  EXPECT_EQ(said.lines().size(), 1u) << said.text.str();
  EXPECT_EQ(counts.key.untagged, 201);
}

}  // namespace
}  // namespace afford
