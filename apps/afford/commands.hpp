// The subcommands of `afford`, one file each (commands/<name>.cpp). Each adds
// its options to the application and returns what runs it once the command
// line is parsed; the front door (main.cpp) runs the one that was given.
#pragma once
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <functional>
#include <string>
#include <vector>

namespace afford {

// What every subcommand shares: the config folder (--config-dir) and the log.
struct FrontDoor {
  std::string config_dir;
  std::string program;  // argv[0]
  std::vector<std::string> args;  // argv[1...]
  spdlog::logger* log = nullptr;
};

struct Command {
  CLI::App* sub = nullptr;
  std::function<int()> run;  // the exit status
};

// The lines a command reading a log prints of what it skipped (nothing for a count of 0): malformed parts of
// the file, RUN_CONFIG events the edge refuses, events without a valid tag of the bus key.
void printLogSkips(long long malformed, long long refused_configs, long long untagged);

Command experimentCommand(CLI::App& app, const FrontDoor& door);
Command experimentsCommand(CLI::App& app, const FrontDoor& door);
Command configCommand(CLI::App& app, const FrontDoor& door);
Command worldCommand(CLI::App& app, const FrontDoor& door);
Command plotCommand(CLI::App& app, const FrontDoor& door);
Command reportCommand(CLI::App& app, const FrontDoor& door);
Command replayCommand(CLI::App& app, const FrontDoor& door);
Command explainCommand(CLI::App& app, const FrontDoor& door);
Command statusCommand(CLI::App& app, const FrontDoor& door);
Command scenarioCommand(CLI::App& app, const FrontDoor& door);
Command processesCommand(CLI::App& app, const FrontDoor& door);
Command cleanCommand(CLI::App& app, const FrontDoor& door);
Command mergeCommand(CLI::App& app, const FrontDoor& door);
Command busKeyCommand(CLI::App& app, const FrontDoor& door);
Command exportCommand(CLI::App& app, const FrontDoor& door);
Command renderCommand(CLI::App& app, const FrontDoor& door);
Command watchCommand(CLI::App& app, const FrontDoor& door);
Command tuneCommand(CLI::App& app, const FrontDoor& door);

}  // namespace afford
