#include "afford/edge_peers.hpp"

#include <algorithm>
#include <cstdlib>

namespace afford {

namespace {

// The entry heard from longest ago, forgotten when the table is full (counted).
template <class Map>
void makeRoom(Map& m, int limit, std::int64_t& forgotten) {
  if (m.size() < static_cast<std::size_t>(std::max(limit, 1))) return;
  m.erase(std::min_element(m.begin(), m.end(), [](const auto& a, const auto& b) { return a.second.order < b.second.order; }));
  ++forgotten;
}

}  // namespace

bool EdgePeers::newerStatus(const process_status_t& st, int limit, std::int64_t& forgotten) {
  const std::string key = st.process + "#" + std::to_string(st.pid);
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
