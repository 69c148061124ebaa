// Keeping multicast on this machine (docs/operating.md): the
// runner moves itself, before it starts any thread or process, into a private
// network namespace whose only interface is loopback with a route for
// 224.0.0.0/4. Every process it starts inherits it, so no packet can leave.
#pragma once
#include <nlohmann/json.hpp>

#include <string>

#include "experiment/schema/codec.hpp"

namespace afford {

enum class NetnsMode { Auto, On, Off };
// As an experiment keeps it: "auto", "on" or "off" (found by argument-dependent lookup from the codec).
nlohmann::json out(const NetnsMode& m);
void in(const nlohmann::json& j, const std::string& path, const codec::Context& c, NetnsMode& m);

// Returns a description of the network the run will use; throws
// std::runtime_error when multicast cannot be kept on this machine.
std::string prepareNetwork(NetnsMode mode);

// True if this namespace routes 224.0.0.0/4 via the loopback device.
bool loopbackMulticastRoute();

}  // namespace afford
