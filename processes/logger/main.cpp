// afford-logger: records a run's channels as a standard LCM log. See node.hpp.
#include "logger/node.hpp"
#include "afford/process_main.hpp"

int main(int argc, char** argv) {
  std::string log_root = afford::defaultLogRoot();
  return afford::processMain(
      argc, argv, {"logger", "afford logger: every channel of a run into logs/<run-id>/"},
      [&](afford::CLIHook& cli) { cli.option("--log-dir", log_root, "folder that receives one sub-folder per run (default: $AFFORD_LOGS, else logs)"); },
      [&](lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const afford::ProtocolConfig& protocol) {
        return std::make_unique<afford::LoggerNode>(lcm, std::move(log), protocol, log_root);
      });
}
