// afford-motivation: FIX, IGN and IMP (paper 2.4.1). See node.hpp for channels.
#include "motivation/node.hpp"

int main(int argc, char** argv) {
  return afford::processMain(
      argc, argv, {"motivation", "afford motivation: intrinsic motivation signal and leaky threshold"},
      [](afford::CLIHook&) {},
      [](lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const afford::ProtocolConfig& protocol) {
        return std::make_unique<afford::MotivationNode>(lcm, std::move(log), protocol);
      });
}
