// afford-motivation: the motivation that motivation.kind names (paper: FIX, IGN and IMP, paper 2.4.1;
// novelty). See node.hpp for channels, component.hpp for writing one.
#include "motivation/node.hpp"
#include "afford/process_main.hpp"

int main(int argc, char** argv) {
  return afford::processMain(
      argc, argv, {"motivation", "afford motivation: intrinsic motivation (motivation.kind: paper, novelty)"},
      [](afford::CLIHook&) {},
      [](lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const afford::ProtocolConfig& protocol) {
        return std::make_unique<afford::MotivationNode>(lcm, std::move(log), protocol);
      });
}
