// afford processes: the registry of processes (afford/processes.hpp) and the protocol's channels
// (afford/protocol.hpp), for scripts and people.
#include <cstdio>
#include <memory>

#include "apps/afford/commands.hpp"
#include "experiment/run/host.hpp"
#include "afford/processes.hpp"
#include "afford/protocol.hpp"

namespace afford {

Command processesCommand(CLI::App& app, const FrontDoor& door) {
  struct Args {
    std::string phase = "all";
    bool recorded = true, channels = false, protocol = false, rules = false;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand("processes", "list the processes of a run, one per line (for scripts), or with "
                                              "the channels each publishes");
  cmd->add_option("--phase", a->phase, "intrinsic, extrinsic, goals or all")
      ->check(CLI::IsMember({"intrinsic", "extrinsic", "goals", "all"}))
      ->capture_default_str();
  cmd->add_flag("!--no-logger", a->recorded, "leave the logger out (a run that is not recorded)");
  cmd->add_flag("--channels", a->channels, "each process with what it does and the channels it publishes");
  cmd->add_flag("--protocol", a->protocol,
                "every channel: its type, who publishes and reads it, whether it is recorded, when (markdown)");
  cmd->add_flag("--rules", a->rules, "each process's inputs: what it takes from each channel, and when (markdown)");
  return {cmd, [a, &door] {
            if (a->protocol) {
              std::printf("%s", protocolTable().c_str());
              return 0;
            }
            if (a->rules) {
              std::printf("%s", inputRulesTable(door.config_dir).c_str());
              return 0;
            }
            for (const ProcessInfo& p : processRegistry()) {
              bool in = a->phase == "all";
              for (const auto& [name, phase] : kPhaseNames) in = in || (a->phase == name && p.in(phase));
              if (!in || (p.recorder && !a->recorded)) continue;
              if (!a->channels) {
                std::printf("%s\n", p.name);
                continue;
              }
              std::string chans;
              for (const char* c : p.publishes) chans += std::string(chans.empty() ? "" : " ") + c;
              std::printf("%-12s %-60s %s\n", p.name, p.summary, chans.empty() ? "-" : chans.c_str());
            }
            return 0;
          }};
}

}  // namespace afford
