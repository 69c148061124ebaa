// The edge's table of peers (afford/edge.hpp), each part bounded by
// protocol.limits.peers (the one heard from longest ago is forgotten, and
// counted):
//   - the last STATUS beat taken from each process and pid (an older or
//     repeated one is not taken again);
//   - on a keyed bus, freshness (docs/security.md#freshness): each sender
//     session's anti-replay window, as IPsec's and WireGuard's (RFC 6479): the
//     highest counter taken and which of the 1024 before it were; a counter
//     taken already, or older than the window, or older than the first one
//     heard from the session, is a message said twice and is dropped. A
//     session not heard yet is taken only if its message was sent less than
//     protocol.freshness_ms ago by its own clock: a recording played back
//     later is old, whoever hears it.
#pragma once
#include <bitset>
#include <cstdint>
#include <map>
#include <string>

#include "afford/auth.hpp"
#include "afford/process_status_t.hpp"

namespace afford {

class EdgePeers {
 public:
  static constexpr std::uint64_t kWindow = 1024;  // counters remembered below a session's highest

  // Is this STATUS newer (by beat) than the last one taken from its process and pid? Takes it if so.
  // `limit`: peers kept at most; `forgotten` counts those evicted.
  bool newerStatus(const process_status_t& st, int limit, std::int64_t& forgotten);

  // Is a message with this stamp new? Takes it if so; else says why not (said twice, too old, stale).
  // `now_ms`: the receiver's clock; `freshness_ms`: how recent a session not heard yet must be (0: any).
  std::string fresh(const Stamp& stamp, std::int64_t now_ms, int freshness_ms, int limit, std::int64_t& forgotten);

 private:
  struct Beat {
    std::int64_t beat = -1;
    std::uint64_t order = 0;  // when it was last updated (for evicting the oldest)
  };
  std::map<std::string, Beat> beats_;  // process#pid -> the last STATUS taken
  struct Window {
    std::uint64_t first = 0;    // the first counter heard: older ones were sent before it was heard, and refused
    std::uint64_t highest = 0;  // the highest counter taken
    std::bitset<kWindow> seen;  // bit k: highest - k was taken
    std::uint64_t order = 0;
  };
  std::map<std::uint64_t, Window> windows_;  // session -> its window
  std::uint64_t order_ = 0;
};

}  // namespace afford
