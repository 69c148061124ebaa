// afford-environment: the world of the run (paper 2.2, 2.3.2). See node.hpp for channels.
#include "environment/node.hpp"
#include "afford/process_main.hpp"

int main(int argc, char** argv) {
  return afford::processMain(
      argc, argv, {"environment", "afford environment: scene, objects, actions"}, [](afford::CLIHook&) {},
      [](lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const afford::ProtocolConfig& protocol) {
        return std::make_unique<afford::EnvironmentNode>(lcm, std::move(log), protocol);
      });
}
