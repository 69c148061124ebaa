// An authenticated bus (docs/security.md). A group of processes may share a
// key; every message each of them sends then ends with a 32-byte tag, the
// keyed BLAKE2b (libsodium's crypto_generichash) of the channel name and the
// message's bytes, and every message each of them receives is dropped unless
// it ends with the right tag, before anything else of it is looked at (the
// edge, afford/edge.hpp, step 0). The tag trails the LCM-encoded message, so
// the wire format of the types is unchanged and lcm-spy still decodes every
// channel (LCM's decoders ignore bytes after a message). Logs hold the
// messages without their tags.
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

class BusKey {
 public:
  static constexpr std::size_t kKeyBytes = 32;
  static constexpr std::size_t kTagBytes = 32;
  static constexpr const char* kEnvironment = "AFFORD_BUS_KEY";

  // Reads a key file; throws std::runtime_error naming the file and what is wrong.
  static BusKey fromFile(const std::filesystem::path& file);
  // Writes a new random key to `file` (mode 0600); never overwrites one.
  static void writeNew(const std::filesystem::path& file);
  explicit BusKey(const std::array<std::uint8_t, kKeyBytes>& key);

  // The tag of `size` bytes sent on `channel`.
  std::array<std::uint8_t, kTagBytes> tag(const std::string& channel, const void* data, std::size_t size) const;
  // The message with its tag appended.
  std::vector<std::uint8_t> tagged(const std::string& channel, const void* data, std::size_t size) const;
  // Do the last kTagBytes of the buffer tag the bytes before them on `channel`?
  bool verify(const std::string& channel, const void* data, std::size_t size_with_tag) const;

 private:
  std::array<std::uint8_t, kKeyBytes> key_;
};

// The key of a command line's --bus-key (`option`, "" if not given), else of
// $AFFORD_BUS_KEY, else none (nullptr). Throws std::runtime_error naming the
// file (and where its name came from) if it cannot be read.
std::shared_ptr<const BusKey> busKeyFrom(const std::string& option);
// Where busKeyFrom found the key: the option's file, the variable's, or "".
std::string busKeySource(const std::string& option);

}  // namespace afford
