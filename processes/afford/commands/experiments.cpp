// afford experiments: list the experiments of the config folder.
#include <cstdio>

#include "afford/commands.hpp"
#include "afford/config.hpp"

namespace afford {

Command experimentsCommand(CLI::App& app, const FrontDoor& door) {
  auto* list = app.add_subcommand("experiments", "list the experiments in the config folder");
  return {list, [&door] {
            for (const auto& n : listExperiments(door.config_dir)) {
              const auto e = loadExperiment(door.config_dir, n);
              std::printf("%-16s %s\n", n.c_str(), e.description.c_str());
            }
            return 0;
          }};
}

}  // namespace afford
