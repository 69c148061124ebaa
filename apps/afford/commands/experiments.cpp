// afford experiments: list the experiments of the config folder.
#include <algorithm>
#include <cstdio>

#include "apps/afford/commands.hpp"
#include "afford/config.hpp"
#include "experiment/design/experiment_file.hpp"

namespace afford {

Command experimentsCommand(CLI::App& app, const FrontDoor& door) {
  auto* list = app.add_subcommand("experiments", "list the experiments in the config folder");
  return {list, [&door] {
            const std::vector<std::string> names = listExperiments(door.config_dir);
            std::size_t width = 0;  // the longest name, so that every description starts in one column
            for (const auto& n : names) width = std::max(width, n.size());
            for (const auto& n : names)
              std::printf("%-*s  %s\n", static_cast<int>(width), n.c_str(),
                          loadExperiment(door.config_dir, n).description.c_str());
            return 0;
          }};
}

}  // namespace afford
