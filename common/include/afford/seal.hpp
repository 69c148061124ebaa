// The integrity digest every message ends with (`int64_t digest`, the last
// field of every type): FNV-1a 64 of all the bytes before it, fingerprint
// included, written big-endian in the last 8 bytes. A receiver drops a message
// whose digest does not match (docs/processes-and-channels.md, "The message
// edge"): corrupted, truncated, mangled or naively forged copies never reach
// a handler. It is a check against accidents and careless forgery, not an
// authentication: anyone on the bus can compute it.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace afford {

// FNV-1a 64 of `n` bytes.
std::uint64_t fnv1a64(const void* data, std::size_t n);
// The FNV-1a 64 state `h` continued over `n` more bytes.
std::uint64_t fnv1a64(std::uint64_t h, const void* data, std::size_t n);

// True if the last 8 bytes of the buffer are the digest of the bytes before them.
bool sealIntact(const void* data, std::size_t n);

// Where a buffer's digest is, in one pass over it: at its end (a message as sealed), `trailer` bytes before its
// end (a sealed message with that many bytes appended: a keyed bus's stamp and tag, afford/auth.hpp), or
// neither (malformed, forged, not a message of ours).
enum class SealAt { End, BeforeTrailer, Neither };
SealAt sealAt(const void* data, std::size_t n, std::size_t trailer);

// Write the digest of buf[0, n-8) into buf[n-8, n); returns it.
std::int64_t sealBuffer(std::uint8_t* buf, std::size_t n);

// The `prev_digest` of a channel's first message (serial 0) in a run: every
// run message names the digest of its channel's previous one, so a copy given
// another serial (re-sealed or not) does not follow the real one and is refused
// before it can take that serial's place. The seed is the request's
// (run_config_t.request: a number the runner draws for each request), so
// nothing published for another request of the same run id, with the same
// configuration or not, follows this one's chain.
std::int64_t chainSeed(const std::string& run_id, const std::string& channel, std::int64_t request);

// Encode `msg` with its digest (also set in msg.digest).
template <class Msg>
std::vector<std::uint8_t> sealed(Msg& msg) {
  msg.digest = 0;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(msg.getEncodedSize()));
  msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  msg.digest = sealBuffer(bytes.data(), bytes.size());
  return bytes;
}

}  // namespace afford
