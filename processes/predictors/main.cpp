// afford-predictors: the 16 perceptrons (paper 2.3.3). See node.hpp for channels.
#include "predictors/node.hpp"
#include "afford/process_main.hpp"

int main(int argc, char** argv) {
  std::string checkpoint_root = afford::defaultLogRoot();
  return afford::processMain(
      argc, argv, {"predictors", "afford predictors: affordance, learning-progress, what- and where-effect"},
      [&](afford::CLIHook& cli) {
        cli.option("--checkpoint-dir", checkpoint_root,
                   "the only folder checkpoints are written in (<dir>/<run-id>/) and read from (an experiment's "
                   "--log-root; default: $AFFORD_LOGS, else logs)");
      },
      [&](lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const afford::ProtocolConfig& protocol) {
        return std::make_unique<afford::PredictorsNode>(lcm, std::move(log), protocol, /*async_effects=*/true,
                                                        checkpoint_root);
      });
}
