#include "afford/seal.hpp"

namespace afford {

std::uint64_t fnv1a64(const void* data, std::size_t n) {
  std::uint64_t h = 0xCBF29CE484222325ull;
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < n; ++i) {
    h ^= p[i];
    h *= 0x100000001B3ull;
  }
  return h;
}

bool sealIntact(const void* data, std::size_t n) {
  if (n < 16) return false;  // a fingerprint and a digest at least
  const auto* p = static_cast<const unsigned char*>(data);
  std::uint64_t stored = 0;
  for (std::size_t i = n - 8; i < n; ++i) stored = (stored << 8) | p[i];
  return stored == fnv1a64(p, n - 8);
}

std::int64_t chainSeed(const std::string& run_id, const std::string& channel) {
  const std::string key = run_id + "\n" + channel;
  return static_cast<std::int64_t>(fnv1a64(key.data(), key.size()));
}

std::int64_t sealBuffer(std::uint8_t* buf, std::size_t n) {
  const std::uint64_t h = fnv1a64(buf, n - 8);
  for (int i = 0; i < 8; ++i) buf[n - 1 - i] = static_cast<std::uint8_t>(h >> (8 * i));
  return static_cast<std::int64_t>(h);
}

}  // namespace afford
