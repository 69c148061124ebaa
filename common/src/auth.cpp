#include "afford/auth.hpp"

#include "afford/seal.hpp"

#include <fcntl.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <mutex>
#include <sstream>
#include <stdexcept>

namespace afford {

namespace {

void initSodium() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (sodium_init() < 0) throw std::runtime_error("libsodium cannot be initialised");
  });
}

int hexDigit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

}  // namespace

BusKey::BusKey(const std::array<std::uint8_t, kKeyBytes>& key) : key_(key) { initSodium(); }

BusKey BusKey::fromFile(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec))
    throw std::runtime_error("bus key " + file.string() + ": not a readable file");
  if (std::filesystem::file_size(file, ec) > 4096)
    throw std::runtime_error("bus key " + file.string() + ": too large to be a key file (64 hex digits)");
  std::ifstream in(file);
  if (!in) throw std::runtime_error("bus key " + file.string() + ": cannot be read: " + std::strerror(errno));
  std::stringstream text;
  text << in.rdbuf();
  std::string digits;
  for (char c : text.str())
    if (c != ' ' && c != '\n' && c != '\r' && c != '\t') digits += c;
  if (digits.size() != 2 * kKeyBytes)
    throw std::runtime_error("bus key " + file.string() + ": expected 64 hexadecimal digits, found " +
                             std::to_string(digits.size()) + " characters (make one with `afford bus-key FILE`)");
  std::array<std::uint8_t, kKeyBytes> key{};
  for (std::size_t i = 0; i < kKeyBytes; ++i) {
    const int hi = hexDigit(digits[2 * i]), lo = hexDigit(digits[2 * i + 1]);
    if (hi < 0 || lo < 0)
      throw std::runtime_error("bus key " + file.string() + ": character " + std::to_string(2 * i + (hi < 0 ? 0 : 1)) +
                               " is not a hexadecimal digit");
    key[i] = static_cast<std::uint8_t>(hi * 16 + lo);
  }
  return BusKey(key);
}

void BusKey::writeNew(const std::filesystem::path& file) {
  initSodium();
  std::array<std::uint8_t, kKeyBytes> key{};
  randombytes_buf(key.data(), key.size());
  std::string text;
  static const char* hex = "0123456789abcdef";
  for (std::uint8_t b : key) {
    text += hex[b >> 4];
    text += hex[b & 15];
  }
  text += '\n';
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) throw std::runtime_error("bus key " + file.string() + ": cannot be created: " + std::strerror(errno));
  const bool ok = ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  const int err = errno;
  ::close(fd);
  sodium_memzero(key.data(), key.size());
  if (!ok) throw std::runtime_error("bus key " + file.string() + ": cannot be written: " + std::strerror(err));
}

std::array<std::uint8_t, BusKey::kTagBytes> BusKey::tag(const std::string& channel, const void* data,
                                                        std::size_t size) const {
  std::array<std::uint8_t, kTagBytes> out{};
  crypto_generichash_state state;
  crypto_generichash_init(&state, key_.data(), key_.size(), out.size());
  // The channel and its terminating zero first: a message is tagged for the channel it is sent on.
  crypto_generichash_update(&state, reinterpret_cast<const unsigned char*>(channel.c_str()), channel.size() + 1);
  crypto_generichash_update(&state, static_cast<const unsigned char*>(data), size);
  crypto_generichash_final(&state, out.data(), out.size());
  return out;
}

namespace {

void putBig(std::uint8_t* out, std::uint64_t v) {
  for (int i = 7; i >= 0; --i, v >>= 8) out[i] = static_cast<std::uint8_t>(v & 0xff);
}
std::uint64_t getBig(const std::uint8_t* in) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | in[i];
  return v;
}

}  // namespace

std::vector<std::uint8_t> BusKey::tagged(const std::string& channel, const void* data, std::size_t size,
                                         const Stamp& stamp) const {
  std::vector<std::uint8_t> out(size + kTrailerBytes);
  if (size > 0) std::memcpy(out.data(), data, size);
  std::uint8_t* s = out.data() + size;
  putBig(s, stamp.session);
  putBig(s + 8, stamp.counter);
  putBig(s + 16, static_cast<std::uint64_t>(stamp.sent_ms));
  const auto t = tag(channel, out.data(), size + kStampBytes);
  std::memcpy(out.data() + size + kStampBytes, t.data(), t.size());
  return out;
}

bool BusKey::verify(const std::string& channel, const void* data, std::size_t size_with_trailer, Stamp* stamp) const {
  if (size_with_trailer < kTrailerBytes) return false;
  const std::size_t stamped = size_with_trailer - kTagBytes;
  const auto want = tag(channel, data, stamped);
  const auto* bytes = static_cast<const unsigned char*>(data);
  if (crypto_verify_32(want.data(), bytes + stamped) != 0) return false;
  if (stamp) {
    const std::uint8_t* s = bytes + stamped - kStampBytes;
    *stamp = {getBig(s), getBig(s + 8), static_cast<std::int64_t>(getBig(s + 16))};
  }
  return true;
}

std::uint64_t BusKey::newSession() {
  initSodium();
  std::uint64_t session = 0;
  randombytes_buf(&session, sizeof session);
  return session;
}

KeyMismatch keyMismatchOf(const BusKey* key, const void* data, std::size_t size) {
  const SealAt at = sealAt(data, size, BusKey::kTrailerBytes);
  if (!key) return at == SealAt::BeforeTrailer ? KeyMismatch::TaggedWithoutKey : KeyMismatch::None;
  if (at == SealAt::End) return KeyMismatch::UntaggedWithKey;
  return at == SealAt::BeforeTrailer ? KeyMismatch::OtherKey : KeyMismatch::None;
}

const char* keyHint(KeyMismatch m) {
  switch (m) {
    case KeyMismatch::TaggedWithoutKey:
      return "tagged messages heard: this bus is keyed; give --bus-key FILE (or $AFFORD_BUS_KEY) with the group's key";
    case KeyMismatch::UntaggedWithKey:
      return "untagged messages heard: this bus is not keyed (or its publishers lack the key); give them the key "
             "(--bus-key), or leave it out here";
    case KeyMismatch::OtherKey:
      return "messages tagged with another key heard: the key given here is not this bus's; give --bus-key the "
             "group's key file";
    case KeyMismatch::None:
      break;
  }
  return "";
}

void KeyMismatches::count(KeyMismatch m) {
  if (m == KeyMismatch::TaggedWithoutKey) ++tagged;
  if (m == KeyMismatch::UntaggedWithKey) ++untagged;
  if (m == KeyMismatch::OtherKey) ++other_key;
}

std::int64_t KeyMismatches::of(KeyMismatch m) const {
  return m == KeyMismatch::TaggedWithoutKey ? tagged
         : m == KeyMismatch::UntaggedWithKey ? untagged
         : m == KeyMismatch::OtherKey        ? other_key
                                             : 0;
}

KeyMismatches KeyMismatches::since(const KeyMismatches& before) const {
  return {tagged - before.tagged, untagged - before.untagged, other_key - before.other_key};
}

std::string KeyMismatches::said() const {
  KeyMismatch most = KeyMismatch::None;
  std::int64_t n = 0;
  for (KeyMismatch m : {KeyMismatch::TaggedWithoutKey, KeyMismatch::UntaggedWithKey, KeyMismatch::OtherKey})
    if (of(m) > n) most = m, n = of(m);
  if (n == 0) return "";
  return std::string(keyHint(most)) + " (" + std::to_string(n) + " such message" + (n == 1 ? "" : "s") + " dropped)";
}

std::string busKeySource(const std::string& option) {
  if (!option.empty()) return option;
  const char* env = std::getenv(BusKey::kEnvironment);
  return env && *env ? std::string(env) : std::string();
}

std::shared_ptr<const BusKey> busKeyFrom(const std::string& option) {
  const std::string file = busKeySource(option);
  if (file.empty()) return nullptr;
  try {
    return std::make_shared<const BusKey>(BusKey::fromFile(file));
  } catch (const std::exception& e) {
    throw std::runtime_error(std::string(e.what()) + (option.empty() ? " (named by $AFFORD_BUS_KEY)" : " (--bus-key)"));
  }
}

}  // namespace afford
