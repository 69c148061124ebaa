// Opening the bus. A udpm URL gets the bounds of LCM's receive path from
// protocol.bus (third_party/lcm: the largest message, the bytes and the
// lifetime of incomplete fragmented messages) as provider options, unless the
// URL sets them itself; other providers (memq://, file://) are opened as given.
#pragma once
#include <lcm/lcm-cpp.hpp>

#include <memory>
#include <string>

#include "afford/config.hpp"

namespace afford {

// `url` with protocol.bus's options added (a udpm URL), else `url`.
std::string busUrl(const std::string& url, const BusConfig& bus);
// The bus at busUrl(url, bus); throws std::runtime_error naming the URL if LCM cannot open it.
std::unique_ptr<lcm::LCM> openBus(const std::string& url, const BusConfig& bus);

}  // namespace afford
