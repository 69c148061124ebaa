// `afford plot DIR`: the paper's figures from an experiment's summary.json, as
// PNG files drawn by gnuplot, each with the CSV of what it shows beside it.
//   fig_affordances.png  final affordance predictions, box plots per action,
//                        object and system (paper Figures 5 and 10)
//   fig_curves_<S>.png   mean affordance predictions over the steps, per action,
//                        one line per object (paper Figures 7 to 9)
//   fig_completion.png   completion steps by number of sub-goals, box plots and
//                        the fit a x^2 + b x (paper Figure 6)
// A sweep's folder: each condition's figures in its own folder, and
//   fig_sweep_mae.png     the runs' final errors per condition and system
//   fig_sweep_success.png the tests' success rate per scenario, per condition
#pragma once
#include <string>
#include <vector>

namespace afford {

// Returns the files written; throws std::runtime_error naming what is missing.
std::vector<std::string> plotExperiment(const std::string& dir);

}  // namespace afford
