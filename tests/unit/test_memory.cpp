// The agent's memory of experiences (issue 11): looks told apart as the eye
// sees them, bounded per look and action, sampled by its key alone, balanced
// over looks and actions, and saved and restored whole.
#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>

#include "environment/environment.hpp"
#include "eye/eye.hpp"
#include "predictors/memory.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {

struct MemoryFixture : ::testing::Test {
  RunConfig config = test::shippedConfig("base", System::IMP);
  MemoryConfig memory = config.predictors.memory;  // the shipped look threshold and shift
  std::vector<std::vector<std::uint8_t>> probes = Environment(config).probeImages();

  // Object `k` of the base world alone at (x, y), as the eye's scan sees it.
  std::vector<std::uint8_t> seen(int k, double x, double y) const {
    RunConfig c = config;
    c.world.objects = {config.world.objects[static_cast<std::size_t>(k)]};
    c.world.objects[0].x = x;
    c.world.objects[0].y = y;
    const Environment env(c);
    Eye eye(c);
    eye.setScene(env.render());
    return eye.scan(0).image;
  }
  static Memory::Ref experience(int action, bool success, const std::vector<std::uint8_t>& image, double tag = 0) {
    auto e = std::make_shared<Experience>();
    e->action = action;
    e->affordance = success;
    e->before_image = image;
    if (success) e->after_image = image;  // what the eye reports with an effect
    e->before_x = tag;
    return e;
  }
};

TEST_F(MemoryFixture, EachObjectOfThePapersWorldIsOneLookWhereverItIsAndTwoAreNeverOne) {
  // In the continuous world a circle's pixels differ from place to place; within the shipped threshold they are
  // still one look, and no two shapes or colours are.
  Memory m(memory, config.eye.focus_side);
  std::mt19937 draw(17);
  std::uniform_real_distribution<double> place(config.world.table_min, config.world.table_max);
  std::map<int, std::set<int>> looks_of;  // object -> looks it was seen as
  for (int n = 0; n < 60; ++n)
    for (int k = 0; k < 9; ++k) looks_of[k].insert(m.see(seen(k, place(draw), place(draw)), n));
  std::map<int, int> object_of;  // look -> object
  for (const auto& [k, looks] : looks_of) {
    EXPECT_EQ(looks.size(), 1u) << config.world.objects[static_cast<std::size_t>(k)].name << " was seen as several looks";
    for (int l : looks) {
      EXPECT_FALSE(object_of.count(l)) << "look " << l << " is two objects";
      object_of[l] = k;
    }
  }
  EXPECT_EQ(m.looks(), 9);
}

TEST_F(MemoryFixture, TheDistanceAllowsTheConfiguredShiftAndNoMore) {
  // A square shifted by one pixel is the same look; by three it is another (its edges differ by about 0.02 per
  // pixel of shift).
  std::vector<std::uint8_t> shifted(probes[0].size(), 0);
  const int side = config.eye.focus_side;
  const auto shift = [&](int dx) {
    std::fill(shifted.begin(), shifted.end(), 0);
    for (int y = 0; y < side; ++y)
      for (int x = 0; x < side; ++x)
        for (int c = 0; c < 3; ++c)
          if (x + dx >= 0 && x + dx < side) shifted[(y * side + x + dx) * 3 + c] = probes[0][(y * side + x) * 3 + c];
    return shifted;
  };
  Memory m(memory, side);
  const int square = m.see(probes[0], 0);
  EXPECT_DOUBLE_EQ(m.distance(shift(1), square), 0.0);
  EXPECT_GT(m.distance(shift(3), square), memory.look_threshold);
  EXPECT_EQ(m.see(shift(1), 1), square);
  EXPECT_NE(m.see(shift(3), 2), square);
}

TEST_F(MemoryFixture, TriedAgoCountsStepsSinceEachActionWasLastTriedOnTheLook) {
  Memory m(memory, config.eye.focus_side);
  const int l = m.see(probes[0], 5);
  EXPECT_EQ(m.triedAgo(l, 5), (Memory::TriedAgo{-1, -1, -1, -1}));
  m.record(l, 5, experience(kTurnRed, false, probes[0]));
  m.record(l, 9, experience(kMove, true, probes[0]));
  EXPECT_EQ(m.triedAgo(l, 20), (Memory::TriedAgo{11, -1, 15, -1}));
  const int other = m.see(probes[4], 21);
  EXPECT_NE(other, l);
  EXPECT_EQ(m.triedAgo(other, 21), (Memory::TriedAgo{-1, -1, -1, -1}));
}

TEST_F(MemoryFixture, EachLookAndActionKeepsItsNewestExperiences) {
  memory.per_look_action = 3;
  Memory m(memory, config.eye.focus_side);
  const int a = m.see(probes[0], 0), b = m.see(probes[1], 0);
  for (int n = 0; n < 10; ++n) m.record(a, n, experience(kMove, true, probes[0], n));
  m.record(b, 10, experience(kMove, false, probes[1], 100));  // one of another look: never pushed out by the many
  EXPECT_EQ(m.experiences(), 4u);
  std::set<double> drawn;
  for (std::int64_t step = 0; step < 200; ++step)
    for (const auto& e : m.sample(ReplaySampling::Uniform, 1, step, 0, 4, false)) drawn.insert(e->before_x);
  EXPECT_EQ(drawn, (std::set<double>{7, 8, 9, 100}));
}

TEST_F(MemoryFixture, SamplesAreKeyedBySeedStepAndPurpose) {
  Memory m(memory, config.eye.focus_side);
  for (int k = 0; k < 6; ++k) {
    const int l = m.see(probes[static_cast<std::size_t>(k)], k);
    for (int n = 0; n < 8; ++n) m.record(l, k, experience(n % kNumActions, n % 3 == 0, probes[static_cast<std::size_t>(k)], k * 10 + n));
  }
  const auto tags = [&](std::int64_t seed, std::int64_t step, std::uint64_t sub, bool effects) {
    std::vector<double> out;
    for (const auto& e : m.sample(ReplaySampling::Balanced, seed, step, sub, 16, effects)) out.push_back(e->before_x);
    return out;
  };
  EXPECT_EQ(tags(1, 50, 0, false), tags(1, 50, 0, false));
  EXPECT_NE(tags(1, 50, 0, false), tags(1, 51, 0, false));
  EXPECT_NE(tags(1, 50, 0, false), tags(2, 50, 0, false));
  EXPECT_NE(tags(1, 50, 0, false), tags(1, 50, 1, false));
  for (const auto& e : m.sample(ReplaySampling::Balanced, 1, 50, 1, 64, true)) EXPECT_TRUE(e->affordance);
}

TEST_F(MemoryFixture, BalancedSamplingDrawsEveryLookAndActionAlikeUniformDrawsEveryExperienceAlike) {
  Memory m(memory, config.eye.focus_side);
  const int common = m.see(probes[0], 0), rare = m.see(probes[5], 0);
  for (int n = 0; n < 30; ++n) m.record(common, n, experience(kMove, true, probes[0], 1));
  m.record(rare, 30, experience(kMove, false, probes[5], 2));
  const auto share = [&](ReplaySampling s) {
    int rare_draws = 0, n = 0;
    for (std::int64_t step = 0; step < 2000; ++step)
      for (const auto& e : m.sample(s, 3, step, 0, 4, false)) rare_draws += e->before_x == 2, ++n;
    return static_cast<double>(rare_draws) / n;
  };
  EXPECT_NEAR(share(ReplaySampling::Balanced), 0.5, 0.03);
  EXPECT_NEAR(share(ReplaySampling::Uniform), 1.0 / 31, 0.01);
}

TEST_F(MemoryFixture, AFullMemoryForgetsTheLookSeenLeastRecently) {
  memory.max_looks = 2;
  Memory m(memory, config.eye.focus_side);
  const int red = m.see(probes[0], 0), green = m.see(probes[1], 1);
  m.record(red, 0, experience(kMove, true, probes[0]));
  m.record(green, 1, experience(kMove, true, probes[1]));
  EXPECT_EQ(m.see(probes[0], 2), red);  // the red square is seen again: the green one is now the oldest
  const int blue = m.see(probes[2], 3);
  EXPECT_EQ(blue, green);  // its slot
  EXPECT_EQ(m.looks(), 2);
  EXPECT_EQ(m.experiences(), 1u);
  EXPECT_EQ(m.triedAgo(blue, 3), (Memory::TriedAgo{-1, -1, -1, -1}));
  EXPECT_EQ(m.see(probes[0], 4), red);
}

TEST_F(MemoryFixture, SaveAndLoadRestoreTheWholeMemory) {
  Memory m(memory, config.eye.focus_side);
  for (int k = 0; k < 4; ++k) {
    const int l = m.see(probes[static_cast<std::size_t>(k)], k);
    m.record(l, k, experience(k % kNumActions, k % 2 == 0, probes[static_cast<std::size_t>(k)], k));
  }
  std::stringstream file;
  m.save(file);
  Memory back(memory, config.eye.focus_side);
  back.load(file, "test");
  Fnv1a h1, h2;
  m.hash(h1);
  back.hash(h2);
  EXPECT_EQ(h1.hex(), h2.hex());
  EXPECT_EQ(back.see(probes[2], 10), m.see(probes[2], 10));
  EXPECT_EQ(back.triedAgo(2, 10), m.triedAgo(2, 10));

  // It comes back with the settings it was kept with, whatever the loader's.
  MemoryConfig one_each = memory;
  one_each.per_look_action = 1;
  Memory smaller(one_each, config.eye.focus_side);
  std::stringstream again;
  m.save(again);
  smaller.load(again, "checkpoint x");
  Fnv1a h3, h4;
  smaller.hash(h3);
  m.hash(h4);
  EXPECT_EQ(h3.hex(), h4.hex());
}

TEST_F(MemoryFixture, ADamagedMemoryIsRefusedSayingWhere) {
  Memory m(memory, config.eye.focus_side);
  const int l = m.see(probes[0], 0);
  m.record(l, 0, experience(kMove, true, probes[0]));
  std::stringstream file;
  m.save(file);
  const std::string bytes = file.str();
  const auto refusal = [&](const std::string& damaged) {
    std::stringstream in(damaged);
    Memory back(memory, config.eye.focus_side);
    try {
      back.load(in, "checkpoint x");
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  for (std::size_t cut : {std::size_t{3}, std::size_t{30}, bytes.size() / 2, bytes.size() - 1}) {
    const std::string why = refusal(bytes.substr(0, cut));
    EXPECT_NE(why.find("checkpoint x: its memory is damaged (truncated"), std::string::npos) << cut << ": " << why;
  }
  // The experience's image size (after the look's image and its counts) made 10: refused, not read past.
  std::string corrupt = bytes;
  const std::size_t image_size = bytes.find(std::string("\x2b\x05\x00\x00", 4), bytes.find(std::string("\x2b\x05\x00\x00", 4)) + 1);
  ASSERT_NE(image_size, std::string::npos);  // 1323 = 0x052b, little-endian: the experience's before-image
  corrupt[image_size] = 10;
  corrupt[image_size + 1] = 0;
  EXPECT_NE(refusal(corrupt).find("of 10 bytes, not 1323"), std::string::npos) << refusal(corrupt);
}

TEST_F(MemoryFixture, AnEmptyMemorySamplesNothingAndAnImageOfAnotherSizeIsRefused) {
  Memory m(memory, config.eye.focus_side);
  EXPECT_TRUE(m.sample(ReplaySampling::Balanced, 1, 1, 0, 3, false).empty());
  EXPECT_THROW(m.see(std::vector<std::uint8_t>(10, 0), 0), std::invalid_argument);
  memory.max_looks = 0;
  EXPECT_THROW(Memory(memory, config.eye.focus_side), ConfigError);
}

}  // namespace
}  // namespace afford
