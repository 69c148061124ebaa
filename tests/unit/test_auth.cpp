// The bus key (afford/auth.hpp): key files read or refused naming what is
// wrong; a tag binds the key, the channel and every byte of the message.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "afford/auth.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {

namespace fs = std::filesystem;

class Auth : public ::testing::Test {
 protected:
  fs::path dir_ = test::tempDir("auth");
  std::string error(const fs::path& f) {
    try {
      BusKey::fromFile(f);
    } catch (const std::exception& e) {
      return e.what();
    }
    return "";
  }
};

TEST_F(Auth, ANewKeyIsPrivateAndNeverOverwritten) {
  const fs::path f = dir_ / "bus.key";
  BusKey::writeNew(f);
  struct stat st {};
  ASSERT_EQ(stat(f.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  std::ifstream in(f);
  std::string text;
  std::getline(in, text);
  EXPECT_EQ(text.size(), 64u);
  EXPECT_THROW(BusKey::writeNew(f), std::runtime_error);
  BusKey::writeNew(dir_ / "other.key");
  EXPECT_EQ(error(f), "");  // it reads back
  const BusKey a = BusKey::fromFile(f), b = BusKey::fromFile(dir_ / "other.key");
  const std::vector<std::uint8_t> m{1, 2, 3};
  EXPECT_NE(a.tag("X", m.data(), m.size()), b.tag("X", m.data(), m.size()));
}

TEST_F(Auth, ABadKeyFileIsRefusedNamingFileAndFault) {
  std::ofstream(dir_ / "short.key") << "abcd\n";
  EXPECT_NE(error(dir_ / "short.key").find("expected 64 hexadecimal digits, found 4"), std::string::npos);
  std::ofstream(dir_ / "nothex.key") << std::string(63, 'a') << "z\n";
  EXPECT_NE(error(dir_ / "nothex.key").find("character 63 is not a hexadecimal digit"), std::string::npos);
  EXPECT_NE(error(dir_ / "absent.key").find("absent.key: not a readable file"), std::string::npos);
  EXPECT_NE(error(dir_).find("not a readable file"), std::string::npos);
}

TEST_F(Auth, ATagBindsTheChannelEveryByteAndTheStamp) {
  BusKey::writeNew(dir_ / "k");
  const BusKey key = BusKey::fromFile(dir_ / "k");
  std::vector<std::uint8_t> m(1000);
  for (std::size_t i = 0; i < m.size(); ++i) m[i] = static_cast<std::uint8_t>(i);
  const Stamp stamp{0x0123456789abcdefULL, 41, 1'764'000'000'123};
  std::vector<std::uint8_t> t = key.tagged("FOCUS", m.data(), m.size(), stamp);
  ASSERT_EQ(t.size(), m.size() + BusKey::kTrailerBytes);
  Stamp read;
  EXPECT_TRUE(key.verify("FOCUS", t.data(), t.size(), &read));
  EXPECT_EQ(read.session, stamp.session);
  EXPECT_EQ(read.counter, stamp.counter);
  EXPECT_EQ(read.sent_ms, stamp.sent_ms);
  EXPECT_FALSE(key.verify("SCENE", t.data(), t.size()));  // the same bytes on another channel
  // Every byte counts: the message's, the stamp's (a counter or a session changed is no longer tagged), the tag's.
  for (std::size_t at : {std::size_t{0}, std::size_t{500}, m.size(), m.size() + 8, m.size() + 16, t.size() - 1}) {
    std::vector<std::uint8_t> u = t;
    u[at] ^= 1;
    EXPECT_FALSE(key.verify("FOCUS", u.data(), u.size())) << at;
  }
  EXPECT_FALSE(key.verify("FOCUS", t.data(), t.size() - 1));
  EXPECT_FALSE(key.verify("FOCUS", t.data(), 40));  // shorter than a trailer
  EXPECT_NE(BusKey::newSession(), BusKey::newSession());
}

TEST_F(Auth, TheOptionComesBeforeTheEnvironment) {
  BusKey::writeNew(dir_ / "option.key");
  setenv(BusKey::kEnvironment, (dir_ / "absent.key").c_str(), 1);
  EXPECT_EQ(busKeySource((dir_ / "option.key").string()), (dir_ / "option.key").string());
  EXPECT_NE(busKeyFrom((dir_ / "option.key").string()), nullptr);
  try {
    busKeyFrom("");
    ADD_FAILURE() << "a missing key file named by the environment was taken";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("$AFFORD_BUS_KEY"), std::string::npos) << e.what();
  }
  unsetenv(BusKey::kEnvironment);
  EXPECT_EQ(busKeyFrom(""), nullptr);
}

}  // namespace
}  // namespace afford
