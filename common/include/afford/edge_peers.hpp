// The processes heard on a bus, each part bounded by protocol.limits.peers
// (the one heard from longest ago is forgotten, and counted):
//   - the last STATUS beat taken from each process (name, pid, host, start):
//     an older or repeated one is not taken again (EdgePeers);
//   - on a keyed bus, freshness (docs/security.md#freshness): each sender
//     session's anti-replay window, as IPsec's and WireGuard's (RFC 6479): the
//     highest counter taken and which of the 1024 before it were; a counter
//     taken already, or older than the window, or older than the first one
//     heard from the session, is a message said twice and is dropped. A
//     session not heard yet is taken only if its message was sent less than
//     protocol.freshness_ms ago by its own clock: a recording played back
//     later is old, whoever hears it (EdgePeers);
//   - the copies of one program (Copies, Instances): the same name from
//     another pid or host. A copy names, in its STATUS (copies), the others it
//     hears; of two copies that hear each other, the later started refuses to
//     serve. A recording's STATUS never names a live process, so a recording
//     played back makes nobody refuse (docs/processes-and-channels.md,
//     "Copies of a process, and runners").
#pragma once
#include <bitset>
#include <chrono>
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "afford/auth.hpp"
#include "afford/process_status_t.hpp"

namespace afford {

// At most this many copies are named in one STATUS (copies): its bound on the wire.
constexpr int kCopiesNamed = 16;

// One program on the bus, as its STATUS says who it is.
struct Instance {
  std::string process, host;
  std::int32_t pid = 0;
  std::int64_t started = 0;  // wall clock microseconds since 1970 (process_status_t.started)

  static Instance of(const process_status_t& st) { return {st.process, st.host, st.pid, st.started}; }
  // This program under `name`: its pid, its host, and its start (the first time this process asked).
  static Instance self(std::string name);
  // As a STATUS names a copy: "PID@HOST/STARTED".
  std::string id() const;
  // "pid P on host H".
  std::string text() const;
  // Does this one come first (it started earlier; then the smaller host, then pid)? The copy that does not
  // refuses to serve; both copies decide alike from the same two STATUS.
  bool before(const Instance& other) const;
  bool operator==(const Instance& o) const { return pid == o.pid && host == o.host && started == o.started; }
};
// "pid P on host H" of an id a STATUS names ("PID@HOST/STARTED"); the id itself if it is not one.
std::string instanceText(const std::string& id);

// The instances of programs heard (a listener's: the runner's), each with the copies its STATUS names.
class Instances {
 public:
  using Clock = std::chrono::steady_clock;
  struct Entry {
    Instance who;
    std::set<std::string> names;  // the copies its latest STATUS names (ids)
    std::string run_id;           // what its latest STATUS says of its run
    std::int64_t config_digest = 0;
    std::int8_t state = 0;
    Clock::time_point first{}, at{};  // first and last heard
    std::uint64_t order = 0;
  };
  // Take a STATUS (from a sender that says its host: one that does not cannot be told apart from its copies).
  void heard(const process_status_t& st, Clock::time_point now, int limit, std::int64_t& forgotten);
  void forget(const Instance& who);
  bool knows(const Instance& who) const;
  // A copy that refuses to serve: an earlier instance of its name, heard within `live`, names it.
  bool refuses(const Instance& who, Clock::time_point now, Clock::duration live) const;
  // The instances of `process` heard within `live`, earliest first.
  std::vector<const Entry*> live(const std::string& process, Clock::time_point now, Clock::duration live) const;

 private:
  std::map<std::string, Entry> entries_;  // process + id -> entry
  std::uint64_t order_ = 0;
};

// The copies of this program that it hears (the same name, another pid or host), and whether it refuses.
class Copies {
 public:
  using Clock = std::chrono::steady_clock;
  explicit Copies(Instance self) : self_(std::move(self)) {}
  enum class Heard {
    Nothing,  // not a copy, or one heard before
    New,      // a copy not heard before: say so, and name it in STATUS at once (it learns it is heard)
    Refuse,   // an earlier copy names this one: this one refuses to serve (refusal())
  };
  // A STATUS of this program's name.
  Heard heard(const process_status_t& st, Clock::time_point now, int limit, std::int64_t& forgotten);
  // The copies to name in STATUS: those heard within `live` (as ids), at most kCopiesNamed.
  std::vector<std::string> named(Clock::time_point now, Clock::duration live) const;
  // Why this one refuses to serve ("" while it serves).
  const std::string& refusal() const { return refusal_; }
  const Instance& self() const { return self_; }
  // "pid P on host H, started earlier (...)" or "... later (it refuses to serve)".
  std::string describe(const Instance& copy) const;

 private:
  Instance self_;
  Instances heard_;
  std::string refusal_;
};

class EdgePeers {
 public:
  static constexpr std::uint64_t kWindow = 1024;  // counters remembered below a session's highest

  // Is this STATUS newer (by beat) than the last one taken from its process (name, pid, host, start)? Takes it
  // if so. `limit`: peers kept at most; `forgotten` counts those evicted.
  bool newerStatus(const process_status_t& st, int limit, std::int64_t& forgotten);

  // Is a message with this stamp new? Takes it if so; else says why not (said twice, too old, stale).
  // `now_ms`: the receiver's clock; `freshness_ms`: how recent a session not heard yet must be (0: any).
  std::string fresh(const Stamp& stamp, std::int64_t now_ms, int freshness_ms, int limit, std::int64_t& forgotten);

 private:
  struct Beat {
    std::int64_t beat = -1;
    std::uint64_t order = 0;  // when it was last updated (for evicting the oldest)
  };
  std::map<std::string, Beat> beats_;  // process#pid@host/started -> the last STATUS taken
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
