// afford report DIR...: a markdown report of experiment output folders, plotted.
#include <cstdio>
#include <memory>

#include "afford/node.hpp"
#include "afford/process_main.hpp"
#include "apps/afford/commands.hpp"
#include "experiment/present/report.hpp"

namespace afford {

Command reportCommand(CLI::App& app, const FrontDoor& door) {
  auto r = std::make_shared<ReportRequest>();
  auto* report = app.add_subcommand(
      "report", "a markdown report of experiment output folders (plotted): what each ran, its tables and figures");
  report->add_option("dirs", r->dirs, "experiment output folders (each an `afford experiment --out`)")->required();
  report->add_option("--out", r->out, "the markdown file; links in it are relative to its folder")->capture_default_str();
  report->add_option("--figures", r->figures,
                     "where each folder's figures are copied, into <label>/ (default: --out without its extension, "
                     "e.g. report/ beside report.md)");
  report->add_option("--wall-seconds", r->wall_seconds, "a wall time to report (the caller's, e.g. of a whole reproduction)");
  report->add_option("--note", r->note, "a paragraph on how the runs were made, put under the table of what ran");
  return {report, [r, &door] {
            r->config_dir = door.config_dir;
            r->docs_dir = installedShareDir().empty() ? std::string(AFFORD_SOURCE_DIR) + "/docs" : installedShareDir() + "/docs";
            const ReportWritten w = writeReport(*r);
            std::printf("%s\n", w.out.c_str());
            return 0;
          }};
}

}  // namespace afford
