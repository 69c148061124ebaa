// afford report DIR...: a markdown report of experiment output folders, plotted.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>

#include "afford/commands.hpp"
#include "afford/report.hpp"

namespace afford {

Command reportCommand(CLI::App& app, const FrontDoor& door) {
  struct Args {
    std::vector<std::string> dirs;
    std::string out = "docs/results.md", figures = "docs/results", note;
    double wall = 0;
  };
  auto a = std::make_shared<Args>();
  auto* report = app.add_subcommand("report", "write docs/results.md from experiment output folders (plotted)");
  report->add_option("dirs", a->dirs, "experiment output folders")->required();
  report->add_option("--out", a->out, "the markdown file")->capture_default_str();
  report->add_option("--figures", a->figures, "where the figures are copied")->capture_default_str();
  report->add_option("--wall-seconds", a->wall, "wall time of the reproduction, to report");
  report->add_option("--note", a->note, "a paragraph on how the runs were made");
  return {report, [a, &door] {
            const std::string link =
                std::filesystem::relative(a->figures, std::filesystem::path(a->out).parent_path()).string();
            const std::string md = writeReport(a->dirs, a->figures, link, a->wall, a->note, door.config_dir);
            std::ofstream(a->out) << md;
            std::printf("%s\n", a->out.c_str());
            return 0;
          }};
}

}  // namespace afford
