// `afford report DIR... --figures DOCDIR`: docs/results.md from experiment
// output folders (each an `afford experiment --out`, plotted): our tables and
// figures beside the paper's numbers.
#pragma once
#include <string>
#include <vector>

namespace afford {

// Markdown text; copies each folder's fig_*.png into <figures_dir>/<experiment>/
// and links them relative to `link_prefix`.
std::string writeReport(const std::vector<std::string>& dirs, const std::string& figures_dir,
                        const std::string& link_prefix, double wall_seconds, const std::string& note,
                        const std::string& config_dir);

}  // namespace afford
