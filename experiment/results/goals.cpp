#include "experiment/results/goals.hpp"

#include <filesystem>
#include <map>

#include "experiment/run/outcome.hpp"

namespace afford {

namespace {
// goal_t's module order.
const std::vector<std::string> kModules{"explore", "colour", "move", "colour_place"};
}  // namespace

GoalsSummary summariseGoals(const std::string& system, const std::vector<std::pair<std::string, const RunOutcome*>>& runs,
                            std::int64_t steps, std::int64_t curve_interval, const std::string& out_dir) {
  GoalsSummary out;
  WholeFile csv_file(std::filesystem::path(out_dir) / ("goals_" + system + ".csv"));
  std::ostream& csv = csv_file.out();
  csv << "system,run_id,step,module,set,reached,actions,found\n";
  // Per interval (its first step) and module: goals ended, reached; and the totals by tenth of the run.
  std::map<std::int64_t, std::vector<std::int64_t>> set, reached;
  std::vector<std::int64_t> first_set(kModules.size()), first_reached(kModules.size()), last_set(kModules.size()),
      last_reached(kModules.size());
  for (std::int64_t s = 0; s < steps; s += curve_interval) {
    set[s].assign(kModules.size(), 0);
    reached[s].assign(kModules.size(), 0);
  }
  const std::int64_t tenth = std::max<std::int64_t>(1, steps / 10);
  for (const auto& [run_id, outcome] : runs)
    for (const GoalBin& b : outcome->goals)
      for (std::size_t m = 0; m < kModules.size() && m < b.set.size(); ++m) {
        if (b.set[m] == 0) continue;
        // Competence counts goals pursued: those found reached when set are counted apart.
        const std::int64_t found = m < b.found.size() ? b.found[m] : 0;
        csv << system << "," << run_id << "," << b.step << "," << kModules[m] << "," << b.set[m] << ","
            << b.reached[m] << "," << b.actions[m] << "," << found << "\n";
        auto& total = out.modules[kModules[m]];
        total.set += b.set[m];
        total.reached += b.reached[m];
        total.actions += b.actions[m];
        total.found += found;
        const std::int64_t pursued = b.set[m] - found, won = b.reached[m] - found;
        if (set.count(b.step)) {
          set[b.step][m] += pursued;
          reached[b.step][m] += won;
        }
        // The first and last tenth of the steps (whole intervals: run.curve_interval divides a tenth).
        if (b.step < tenth) {
          first_set[m] += pursued;
          first_reached[m] += won;
        }
        if (b.step >= steps - tenth) {
          last_set[m] += pursued;
          last_reached[m] += won;
        }
      }
  csv_file.commit();
  const auto share = [](std::int64_t k, std::int64_t n) {
    return n > 0 ? Nullable<double>(static_cast<double>(k) / static_cast<double>(n)) : Nullable<double>();
  };
  for (const auto& [step, counts] : set) out.steps.push_back(step);
  for (std::size_t m = 0; m < kModules.size(); ++m) {
    auto it = out.modules.find(kModules[m]);
    if (it == out.modules.end()) continue;
    GoalModuleSummary& s = it->second;
    const bool explore = m == 0;  // explorations are random actions, not goals to reach: no competence
    if (!explore) {
      s.first_tenth = share(first_reached[m], first_set[m]);
      s.last_tenth = share(last_reached[m], last_set[m]);
    }
    for (const auto& [step, counts] : set) {
      std::int64_t all = 0;
      for (std::int64_t c : counts) all += c;
      s.competence.push_back(explore ? Nullable<double>() : share(reached[step][m], counts[m]));
      s.chosen.push_back(all > 0 ? static_cast<double>(counts[m]) / static_cast<double>(all) : 0.0);
      s.reached_per_run.push_back(static_cast<double>(reached[step][m]) / static_cast<double>(std::max<std::size_t>(1, runs.size())));
    }
  }
  return out;
}

}  // namespace afford
