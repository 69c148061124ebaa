#include "afford/edge_peers.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <tuple>

namespace afford {

namespace {

std::string keyOf(const Instance& who) { return who.process + "#" + who.id(); }

// The entry heard from longest ago, forgotten when the table is full (counted).
template <class Map>
void makeRoom(Map& m, int limit, std::int64_t& forgotten) {
  if (m.size() < static_cast<std::size_t>(std::max(limit, 1))) return;
  m.erase(std::min_element(m.begin(), m.end(), [](const auto& a, const auto& b) { return a.second.order < b.second.order; }));
  ++forgotten;
}

}  // namespace

// ---- who is who ----------------------------------------------------------------------------

Instance Instance::self(std::string name) {
  char host[256] = {};
  if (gethostname(host, sizeof host - 1) != 0) host[0] = '\0';
  // One start for the whole process (its first node or runner): its nodes, a node made anew in it, its runner's
  // drivers one after another are one program each, whose STATUS differ by name only.
  static const std::int64_t started =
      std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
  return {std::move(name), host[0] ? std::string(host) : std::string("?"), static_cast<std::int32_t>(getpid()), started};
}

std::string Instance::id() const { return std::to_string(pid) + "@" + host + "/" + std::to_string(started); }

std::string Instance::text() const { return "pid " + std::to_string(pid) + " on host " + host; }

bool Instance::before(const Instance& other) const {
  return std::tie(started, host, pid) < std::tie(other.started, other.host, other.pid);
}

std::string instanceText(const std::string& id) {
  const auto at = id.find('@'), slash = id.rfind('/');
  if (at == std::string::npos || slash == std::string::npos || slash < at) return id;
  return "pid " + id.substr(0, at) + " on host " + id.substr(at + 1, slash - at - 1);
}

void Instances::heard(const process_status_t& st, Clock::time_point now, int limit, std::int64_t& forgotten) {
  const Instance who = Instance::of(st);
  if (who.host.empty()) return;
  const std::string key = keyOf(who);
  auto it = entries_.find(key);
  if (it == entries_.end()) {
    makeRoom(entries_, limit, forgotten);
    it = entries_.emplace(key, Entry{}).first;
    it->second.who = who;
    it->second.first = now;
  }
  Entry& e = it->second;
  e.names = std::set<std::string>(st.copies.begin(), st.copies.end());
  e.run_id = st.run_id;
  e.config_digest = st.config_digest;
  e.state = st.state;
  e.at = now;
  e.order = ++order_;
}

void Instances::forget(const Instance& who) { entries_.erase(keyOf(who)); }

bool Instances::knows(const Instance& who) const { return entries_.count(keyOf(who)) > 0; }

bool Instances::refuses(const Instance& who, Clock::time_point now, Clock::duration live) const {
  for (const auto& [key, e] : entries_)
    if (e.who.process == who.process && !(e.who == who) && now - e.at <= live && e.who.before(who) &&
        e.names.count(who.id()))
      return true;
  return false;
}

std::vector<const Instances::Entry*> Instances::live(const std::string& process, Clock::time_point now,
                                                     Clock::duration live) const {
  std::vector<const Entry*> out;
  for (const auto& [key, e] : entries_)
    if (e.who.process == process && now - e.at <= live) out.push_back(&e);
  std::sort(out.begin(), out.end(), [](const Entry* a, const Entry* b) { return a->who.before(b->who); });
  return out;
}

// ---- this program's copies ------------------------------------------------------------------

Copies::Heard Copies::heard(const process_status_t& st, Clock::time_point now, int limit, std::int64_t& forgotten) {
  const Instance who = Instance::of(st);
  // Not a copy: another program, one that cannot say its host, or this process itself (an earlier node of
  // this process restarted in it says the same pid and host).
  if (st.process != self_.process || who.host.empty() || (who.pid == self_.pid && who.host == self_.host))
    return Heard::Nothing;
  const bool names_me = std::find(st.copies.begin(), st.copies.end(), self_.id()) != st.copies.end();
  if (st.state == process_status_t::FAILED && st.run_id.empty() && names_me && self_.before(who)) {
    heard_.forget(who);  // a later copy that refused, leaving: no longer named
    return Heard::Nothing;
  }
  const bool known = heard_.knows(who);
  heard_.heard(st, now, limit, forgotten);
  if (names_me && who.before(self_) && refusal_.empty()) {
    refusal_ = "another copy of " + self_.process + " serves this bus: " + who.text() +
               ", started earlier; this one (" + self_.text() +
               ") refuses to serve (of two copies, the later one does: stop one of them, or give this one "
               "another bus)";
    return Heard::Refuse;
  }
  return known ? Heard::Nothing : Heard::New;
}

std::vector<std::string> Copies::named(Clock::time_point now, Clock::duration live) const {
  std::vector<std::string> ids;
  for (const Instances::Entry* e : heard_.live(self_.process, now, live))
    if (static_cast<int>(ids.size()) < kCopiesNamed) ids.push_back(e->who.id());
  return ids;
}

std::string Copies::describe(const Instance& copy) const {
  return copy.text() + (copy.before(self_) ? ", started earlier (this one refuses once it is named by that one, which "
                                             "a recording's STATUS never does)"
                                           : ", started later (it refuses to serve)");
}

// ---- beats and freshness --------------------------------------------------------------------

bool EdgePeers::newerStatus(const process_status_t& st, int limit, std::int64_t& forgotten) {
  const std::string key = keyOf(Instance::of(st));
  auto it = beats_.find(key);
  if (it != beats_.end()) {
    if (st.beat <= it->second.beat) return false;
    it->second = {st.beat, ++order_};
    return true;
  }
  makeRoom(beats_, limit, forgotten);
  beats_[key] = {st.beat, ++order_};
  return true;
}

std::string EdgePeers::fresh(const Stamp& stamp, std::int64_t now_ms, int freshness_ms, int limit,
                             std::int64_t& forgotten) {
  const std::uint64_t c = stamp.counter;
  auto it = windows_.find(stamp.session);
  if (it == windows_.end()) {
    // A session not heard yet: a process started since, or one heard before this process started (or forgotten).
    const std::int64_t age = now_ms - stamp.sent_ms;
    if (freshness_ms > 0 && std::llabs(age) > freshness_ms)
      return "a sender not heard yet, whose message was sent " + std::to_string(age / 1000) +
             " s ago by its clock (more than protocol.freshness_ms): a message said again";
    makeRoom(windows_, limit, forgotten);
    Window w;
    w.first = w.highest = c;
    w.seen.set(0);
    w.order = ++order_;
    windows_.emplace(stamp.session, w);
    return "";
  }
  Window& w = it->second;
  w.order = ++order_;
  if (c > w.highest) {
    const std::uint64_t shift = c - w.highest;
    w.seen = shift >= kWindow ? std::bitset<kWindow>() : w.seen << shift;
    w.seen.set(0);
    w.highest = c;
    return "";
  }
  if (c < w.first) return "counter " + std::to_string(c) + " was sent before this sender was first heard (a message said again)";
  const std::uint64_t back = w.highest - c;
  if (back >= kWindow) return "counter " + std::to_string(c) + " is older than the window (a message said again)";
  if (w.seen.test(back)) return "counter " + std::to_string(c) + " was taken already (a message said twice)";
  w.seen.set(back);
  return "";
}

}  // namespace afford
