#include "afford/bus.hpp"

#include <stdexcept>

namespace afford {

namespace {
bool hasOption(const std::string& query, const std::string& key) {
  std::size_t at = 0;
  while (at <= query.size()) {
    const std::size_t end = std::min(query.find('&', at), query.size());
    const std::string item = query.substr(at, end - at);
    if (item == key || item.rfind(key + "=", 0) == 0) return true;
    at = end + 1;
  }
  return false;
}
}  // namespace

std::string withBusOption(const std::string& url, const std::string& key, long long value) {
  if (url.rfind("udpm://", 0) != 0) return url;
  const std::size_t q = url.find('?');
  if (q != std::string::npos && hasOption(url.substr(q + 1), key)) return url;
  const char* sep = q == std::string::npos ? "?" : (q + 1 == url.size() ? "" : "&");
  return url + sep + key + "=" + std::to_string(value);
}

std::string busUrl(const std::string& url, const BusConfig& bus) {
  std::string out = url;
  out = withBusOption(out, "max_message_size", bus.max_message_bytes);
  out = withBusOption(out, "fragment_buffer_size", bus.fragment_bytes);
  out = withBusOption(out, "fragment_timeout_ms", bus.fragment_timeout_ms);
  out = withBusOption(out, "receive_queue_size", bus.queue_bytes);
  return out;
}

int pumpBus(lcm::LCM& lcm, int wait_ms, int most) {
  int handled = 0;
  while (handled < most && lcm.handleTimeout(0) > 0) ++handled;
  if (handled > 0 || wait_ms <= 0 || lcm.handleTimeout(wait_ms) <= 0) return handled;
  ++handled;
  while (handled < most && lcm.handleTimeout(0) > 0) ++handled;
  return handled;
}

std::unique_ptr<lcm::LCM> openBus(const std::string& url, const BusConfig& bus) {
  // udpm's receive path is the one patched and bounded (third_party/lcm); memq is in-process.
  if (url.rfind("udpm://", 0) != 0 && url.rfind("memq://", 0) != 0)
    throw std::runtime_error("LCM URL '" + url + "': afford's processes speak over udpm:// (or memq:// in one "
                             "process), whose receive path is bounded");
  auto lcm = std::make_unique<lcm::LCM>(busUrl(url, bus));
  if (!lcm->good())
    throw std::runtime_error("cannot open LCM at '" + url +
                             "' (is there a multicast route? see README: network namespace)");
  return lcm;
}

}  // namespace afford
