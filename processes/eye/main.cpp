// afford-eye: gaze, saliency, effects (paper 2.3.1). See node.hpp for channels.
#include "eye/node.hpp"

int main(int argc, char** argv) {
  return afford::processMain(
      argc, argv, {"eye", "afford eye: saliency scans, focus images, effect detection"}, [](afford::CLIHook&) {},
      [](lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const afford::ProtocolConfig& protocol) {
        return std::make_unique<afford::EyeNode>(lcm, std::move(log), protocol);
      });
}
