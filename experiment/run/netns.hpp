// Keeping multicast on this machine (docs/operating.md): the
// runner moves itself, before it starts any thread or process, into a private
// network namespace whose only interface is loopback with a route for
// 224.0.0.0/4. Every process it starts inherits it, so no packet can leave.
#pragma once
#include <string>

namespace afford {

enum class NetnsMode { Auto, On, Off };

// Returns a description of the network the run will use; throws
// std::runtime_error when multicast cannot be kept on this machine.
std::string prepareNetwork(NetnsMode mode);

// True if this namespace routes 224.0.0.0/4 via the loopback device.
bool loopbackMulticastRoute();

}  // namespace afford
