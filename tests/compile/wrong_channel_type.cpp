// Must NOT compile: SCENE carries scene_t, and this handler takes focus_t
// (ctest Protocol.SubscribingAChannelWithAnotherTypeDoesNotCompile checks the
// compiler's message).
#include <spdlog/sinks/null_sink.h>

#include "afford/edge.hpp"

int main() {
  lcm::LCM lcm("memq://");
  afford::ProtocolConfig protocol;
  afford::Edge edge(lcm, std::make_shared<spdlog::logger>("x", std::make_shared<spdlog::sinks::null_sink_mt>()), "x",
                    protocol);
  edge.subscribe(afford::ch::scene, [](const afford::focus_t&) { return afford::Turn::take(); }, afford::Scope::Run,
                 afford::Order::Serial);
}
