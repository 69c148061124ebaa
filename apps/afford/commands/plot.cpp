// afford plot DIR: draw the paper's figures from an experiment's output folder.
#include <cstdio>
#include <memory>

#include "apps/afford/commands.hpp"
#include "experiment/present/plots.hpp"

namespace afford {

Command plotCommand(CLI::App& app, const FrontDoor&) {
  auto dir = std::make_shared<std::string>();
  auto* plot = app.add_subcommand("plot", "draw the paper's figures (PNG + CSV) from an experiment's output folder");
  plot->add_option("dir", *dir, "folder with summary.json (an experiment's --out)")->required();
  return {plot, [dir] {
            for (const auto& f : plotExperiment(*dir)) std::printf("%s\n", f.c_str());
            return 0;
          }};
}

}  // namespace afford
