// Opening the bus. A udpm URL gets the bounds of LCM's receive path from
// protocol.bus (third_party/lcm: the largest message, the bytes and the
// lifetime of incomplete fragmented messages, the bytes of messages waiting
// to be handled) as provider options, unless the URL sets them itself.
// memq:// (one process) is opened as given; other providers are refused.
#pragma once
#include <lcm/lcm-cpp.hpp>

#include <memory>
#include <string>

#include "afford/config.hpp"

namespace afford {

// `url` with protocol.bus's options added (a udpm URL), else `url`.
std::string busUrl(const std::string& url, const BusConfig& bus);
// A udpm `url` with the provider option `key`=`value` added unless it sets `key` itself; other URLs as given.
std::string withBusOption(const std::string& url, const std::string& key, long long value);
// The bus at busUrl(url, bus); throws std::runtime_error naming the URL if it is neither udpm://
// nor memq://, or if LCM cannot open it.
std::unique_ptr<lcm::LCM> openBus(const std::string& url, const BusConfig& bus);

// The one loop step of every listener (a process, the runner, replay, afford status, the viewer): hand
// every message pending on the bus to its subscribers, at most `most` of them; if none was pending, wait
// up to `wait_ms` for one and then do the same. A burst is taken off LCM's queue at once (what waits
// there is held in memory). Returns how many were handled.
int pumpBus(lcm::LCM& lcm, int wait_ms, int most = 1000);

}  // namespace afford
