// afford-eye: gaze, saliency, effects (paper 2.3.1). See node.hpp for channels.
#include <stdexcept>

#include "eye/node.hpp"
#include "afford/process_main.hpp"

int main(int argc, char** argv) {
  std::string speculate = "on";
  return afford::processMain(
      argc, argv, {"eye", "afford eye: saliency scans, focus images, effect detection"},
      [&](afford::CLIHook& cli) {
        cli.option("--speculate", speculate,
                   "on or off: while a decision is pending, scan the scene a pass would ask for (on pays where a "
                   "core is free; on a full machine the scan an action discards takes a core from another run)");
      },
      [&](lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const afford::ProtocolConfig& protocol) {
        if (speculate != "on" && speculate != "off")
          throw std::invalid_argument("--speculate '" + speculate + "': give on or off");
        return std::make_unique<afford::EyeNode>(lcm, std::move(log), protocol, speculate == "on");
      });
}
