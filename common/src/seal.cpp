#include "afford/seal.hpp"

#include <cstring>

namespace afford {

namespace {
constexpr std::uint64_t kPrime = 0x100000001B3ull;
// A zero byte only multiplies the state by the prime, so eight zero bytes
// multiply it by the prime's eighth power (mod 2^64): a word of zeros, common
// in weights never trained and in mostly black images, costs one step, not eight.
constexpr std::uint64_t kPrime8 = kPrime * kPrime * kPrime * kPrime * kPrime * kPrime * kPrime * kPrime;

std::uint64_t bigEndian64(const unsigned char* p) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | p[i];
  return v;
}
}  // namespace

std::uint64_t fnv1a64(std::uint64_t h, const void* data, std::size_t n) {
  const auto* p = static_cast<const unsigned char*>(data);
  std::size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    std::uint64_t word;
    std::memcpy(&word, p + i, sizeof word);
    if (word == 0) {
      h *= kPrime8;
      continue;
    }
    for (std::size_t j = i; j < i + 8; ++j) {
      h ^= p[j];
      h *= kPrime;
    }
  }
  for (; i < n; ++i) {
    h ^= p[i];
    h *= kPrime;
  }
  return h;
}

std::uint64_t fnv1a64(const void* data, std::size_t n) { return fnv1a64(0xCBF29CE484222325ull, data, n); }

bool sealIntact(const void* data, std::size_t n) {
  if (n < 16) return false;  // a fingerprint and a digest at least
  const auto* p = static_cast<const unsigned char*>(data);
  return bigEndian64(p + n - 8) == fnv1a64(p, n - 8);
}

SealAt sealAt(const void* data, std::size_t n, std::size_t trailer) {
  const auto* p = static_cast<const unsigned char*>(data);
  if (n < 16) return SealAt::Neither;
  // The digest over the bytes before a trailer's would-be digest is a state on the way to the whole one's.
  const bool trailed = trailer > 0 && n >= trailer + 16;
  std::uint64_t h = 0xCBF29CE484222325ull;
  bool before_trailer = false;
  if (trailed) {
    const std::size_t sealed = n - trailer;  // the message's own bytes, its digest last
    h = fnv1a64(h, p, sealed - 8);
    before_trailer = h == bigEndian64(p + sealed - 8);
    h = fnv1a64(h, p + sealed - 8, trailer);  // its digest and the trailer but the trailer's last 8
  } else {
    h = fnv1a64(h, p, n - 8);
  }
  if (h == bigEndian64(p + n - 8)) return SealAt::End;
  return before_trailer ? SealAt::BeforeTrailer : SealAt::Neither;
}

std::int64_t chainSeed(const std::string& run_id, const std::string& channel, std::int64_t request) {
  const std::string key = run_id + "\n" + channel + "\n";
  std::uint8_t r[8];
  for (int i = 0; i < 8; ++i) r[i] = static_cast<std::uint8_t>(static_cast<std::uint64_t>(request) >> (56 - 8 * i));
  return static_cast<std::int64_t>(fnv1a64(fnv1a64(key.data(), key.size()), r, sizeof r));
}

std::int64_t sealBuffer(std::uint8_t* buf, std::size_t n) {
  const std::uint64_t h = fnv1a64(buf, n - 8);
  for (int i = 0; i < 8; ++i) buf[n - 1 - i] = static_cast<std::uint8_t>(h >> (8 * i));
  return static_cast<std::int64_t>(h);
}

}  // namespace afford
