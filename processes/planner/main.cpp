// afford-planner: Algorithm 2 in the extrinsic phase. See node.hpp for channels.
#include "planner/node.hpp"
#include "afford/process_main.hpp"

int main(int argc, char** argv) {
  return afford::processMain(
      argc, argv, {"planner", "afford planner: goal-based one-step planning (extrinsic phase)"},
      [](afford::CLIHook&) {},
      [](lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const afford::ProtocolConfig& protocol) {
        return std::make_unique<afford::PlannerNode>(lcm, std::move(log), protocol);
      });
}
