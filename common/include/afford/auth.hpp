// An authenticated bus (docs/security.md). A group of processes may share a
// key; every message each of them sends then ends with a stamp and a 32-byte
// tag. The stamp says who sent it and when: the sender's session (a random
// number drawn when its edge is made, so new at each start of a process), a
// counter of what that session has sent, and the sender's clock in
// milliseconds. The tag is the keyed BLAKE2b (libsodium's crypto_generichash)
// of the channel name, the message's bytes and the stamp. Every message a
// member receives is dropped unless it ends with the right tag, before
// anything else of it is looked at (the edge, afford/edge.hpp, step 0); the
// stamp then lets the edge drop a message said twice (afford/edge_peers.hpp).
// The trailer follows the LCM-encoded message, so the wire format of the
// types is unchanged and lcm-spy still decodes every channel (LCM's decoders
// ignore bytes after a message). Logs hold the messages without trailers.
//
// A key file holds the key as 64 hexadecimal digits (one line). A process
// takes it from its --bus-key FILE, else from the file the environment
// variable AFFORD_BUS_KEY names; without either, it sends and takes messages
// without tags (a bus anyone who reaches it can speak on).
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace afford {

// Who sent a tagged message and when (under its tag): big-endian on the wire.
struct Stamp {
  std::uint64_t session = 0;  // the sender's, new at each start
  std::uint64_t counter = 0;  // what the session sent before this one
  std::int64_t sent_ms = 0;   // the sender's clock (ms since 1970): a session not heard yet must be recent
};

class BusKey {
 public:
  static constexpr std::size_t kKeyBytes = 32;
  static constexpr std::size_t kTagBytes = 32;
  static constexpr std::size_t kStampBytes = 24;
  static constexpr std::size_t kTrailerBytes = kStampBytes + kTagBytes;  // what a tagged message ends with
  static constexpr const char* kEnvironment = "AFFORD_BUS_KEY";

  // Reads a key file; throws std::runtime_error naming the file and what is wrong.
  static BusKey fromFile(const std::filesystem::path& file);
  // Writes a new random key to `file` (mode 0600); never overwrites one.
  static void writeNew(const std::filesystem::path& file);
  explicit BusKey(const std::array<std::uint8_t, kKeyBytes>& key);

  // The tag of `size` bytes sent on `channel` followed by their stamp's kStampBytes.
  std::array<std::uint8_t, kTagBytes> tag(const std::string& channel, const void* data, std::size_t size) const;
  // The message with its stamp and tag appended.
  std::vector<std::uint8_t> tagged(const std::string& channel, const void* data, std::size_t size,
                                   const Stamp& stamp) const;
  // Do the last kTrailerBytes of the buffer stamp and tag the bytes before them on `channel`? The stamp, if so.
  bool verify(const std::string& channel, const void* data, std::size_t size_with_trailer, Stamp* stamp = nullptr) const;
  // A new random session (libsodium's generator: not the runs' keyed one, and no decision reads it).
  static std::uint64_t newSession();
  // A new number for a request of a run (run_config_t.request), from the same generator.
  static std::int64_t newRequest() { return static_cast<std::int64_t>(newSession()); }

 private:
  std::array<std::uint8_t, kKeyBytes> key_;
};

// A message a reader does not take because its key, or its lack of one, does not fit the bus: told from the
// message's structure (where its digest is: at its end, or kTrailerBytes before it, afford/seal.hpp), never
// from what a decoder made of it.
enum class KeyMismatch {
  None,              // the key fits, or the message is none of ours (malformed, forged): dropped as such
  TaggedWithoutKey,  // a reader without a key heard a tagged message: the bus is keyed
  UntaggedWithKey,   // a keyed reader heard an untagged message: the bus is not keyed, or its publisher lacks the key
  OtherKey,          // a keyed reader heard a tagged message its key does not verify: another key (or channel)
};
// Why `key` (nullptr: none) does not take these bytes; with a key, ask only once verify() has failed.
KeyMismatch keyMismatchOf(const BusKey* key, const void* data, std::size_t size);
// The one line that names the fix ("" for None).
const char* keyHint(KeyMismatch m);

// Messages dropped for a key that does not fit, by kind: what a wait that hears nobody says.
struct KeyMismatches {
  std::int64_t tagged = 0, untagged = 0, other_key = 0;  // TaggedWithoutKey, UntaggedWithKey, OtherKey
  void count(KeyMismatch m);
  std::int64_t of(KeyMismatch m) const;
  KeyMismatches since(const KeyMismatches& before) const;
  // The most frequent kind's hint and count ("tagged messages heard: ...; give --bus-key ... (240 dropped)"), or "".
  std::string said() const;
};

// The key of a command line's --bus-key (`option`, "" if not given), else of
// $AFFORD_BUS_KEY, else none (nullptr). Throws std::runtime_error naming the
// file (and where its name came from) if it cannot be read.
std::shared_ptr<const BusKey> busKeyFrom(const std::string& option);
// Where busKeyFrom found the key: the option's file, the variable's, or "".
std::string busKeySource(const std::string& option);

}  // namespace afford
