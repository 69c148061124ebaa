// afford-predictors: the 16 perceptrons (paper 2.3.3). See node.hpp for channels.
#include "predictors/node.hpp"

int main(int argc, char** argv) {
  return afford::processMain(
      argc, argv, {"predictors", "afford predictors: affordance, learning-progress, what- and where-effect"},
      [](afford::CLIHook&) {},
      [](lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const afford::ProtocolConfig& protocol) {
        return std::make_unique<afford::PredictorsNode>(lcm, std::move(log), protocol);
      });
}
