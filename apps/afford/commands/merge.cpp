// afford merge DIR... --out OUT: join the folders of an experiment's shards
// (`afford experiment ... --shard i/n`) into the folder one machine running
// the whole experiment would have written. Nothing is run: every run's outcome
// comes from the shard that ran it, and the summary is made from them all.
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>

#include <nlohmann/json.hpp>

#include "apps/afford/commands.hpp"
#include "afford/config.hpp"
#include "experiment/experiment.hpp"
#include "experiment/schema/summary.hpp"
#include "experiment/state.hpp"

namespace afford {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// What a shard was asked, apart from which shard it is and how it ran: its plan, and the commands it ran in
// place of shipped processes.
json planOptions(const ExperimentRequest& o) {
  json plan = toJsonOf(o.plan);
  if (!o.host.processes.empty()) plan["processes"] = o.host.processes;
  return plan;
}

ExperimentRequest mergeOptions(const std::vector<std::string>& dirs, const std::string& out) {
  if (dirs.empty()) throw ConfigError("afford merge: give the shards' folders");
  std::map<int, std::string> seen;  // shard index -> folder
  json first_plan;
  ExperimentRequest o;
  int count = 0;
  for (const auto& dir : dirs) {
    if (fs::exists(out) && fs::exists(dir) && fs::equivalent(dir, out))
      throw ConfigError("afford merge: --out " + out + " is one of the shards; choose another folder");
    if (!fs::exists(statePath(dir)))
      throw ConfigError("afford merge: " + dir + " holds no experiment (no " + statePath(dir).string() + ")");
    const ExperimentState state = readState(dir);
    const ExperimentRequest& options = state.options;
    if (!options.host.shard_count)
      throw ConfigError("afford merge: " + dir + " is not a shard (it ran without --shard)");
    const int index = options.host.shard_index, n = options.host.shard_count;
    if (state.state != "finished")
      throw ConfigError("afford merge: shard " + std::to_string(index) + "/" + std::to_string(n) + " in " + dir +
                        " did not finish (" + state.state + "): resume it with `" +
                        (state.resume.empty() ? "afford experiment --resume --out " + dir : state.resume) + "`");
    if (seen.empty()) {
      count = n;
      first_plan = planOptions(options);
      o = options;
      try {  // where the shards ran, said in the merged summary
        const json summary = readSummaryJson(dir);
        const std::string file = (fs::path(dir) / "summary.json").string();
        o.merged_network = isSweepSummary(summary) ? sweepSummaryFromJson(summary, file).network
                                                   : summaryFromJson(summary, file).network;
      } catch (const SummaryError& e) {
        throw ConfigError(std::string("afford merge: ") + e.what());
      }
    } else {
      if (n != count)
        throw ConfigError("afford merge: " + dir + " is shard " + std::to_string(index) + " of " + std::to_string(n) +
                          ", " + seen.begin()->second + " one of " + std::to_string(count));
      const json plan = planOptions(options);
      for (const auto& [key, value] : first_plan.items())
        if (plan.value(key, json()) != value)
          throw ConfigError("afford merge: " + dir + " and " + seen.begin()->second + " are shards of different "
                            "experiments (option '" + key + "': " + plan.value(key, json()).dump() + " vs " +
                            value.dump() + ")");
      if (plan.size() != first_plan.size())
        throw ConfigError("afford merge: " + dir + " and " + seen.begin()->second + " are shards of different "
                          "experiments (one ran commands of its own in place of shipped processes, the other not)");
    }
    if (seen.count(index))
      throw ConfigError("afford merge: " + dir + " and " + seen[index] + " are both shard " + std::to_string(index) +
                        "/" + std::to_string(n));
    seen[index] = dir;
  }
  std::string missing;
  for (int i = 0; i < count; ++i)
    if (!seen.count(i)) missing += (missing.empty() ? "" : ", ") + std::to_string(i) + "/" + std::to_string(count);
  if (!missing.empty()) throw ConfigError("afford merge: shard(s) " + missing + " missing: give every shard's folder");
  o.host.shard_index = o.host.shard_count = 0;
  o.write.out_dir = out;
  o.resume = false;
  o.host.reuse_agents = false;  // the shards stored their agents
  for (const auto& [i, dir] : seen) o.merged_from.push_back(fs::absolute(dir).lexically_normal().string());
  return o;
}

}  // namespace

Command mergeCommand(CLI::App& app, const FrontDoor& door) {
  struct Args {
    std::vector<std::string> dirs;
    std::string out = "out";
    bool quiet = false, replace = false;
  };
  auto a = std::make_shared<Args>();
  auto* merge = app.add_subcommand(
      "merge", "join the folders of an experiment's shards (afford experiment --shard i/n) into one, as if one "
               "machine had run it all");
  merge->add_option("dirs", a->dirs, "the shards' output folders (every shard, once)")->required();
  merge->add_option("--out", a->out, "folder for the merged summary.json and CSV files")->capture_default_str();
  merge->add_flag("--quiet", a->quiet, "do not print the table at the end");
  merge->add_flag("--replace", a->replace, "--out holds a finished experiment: remove its files first");
  return {merge, [a, &door] {
            ExperimentRequest o = mergeOptions(a->dirs, a->out);
            o.write.quiet = a->quiet;
            o.write.replace = a->replace;
            o.write.program = door.program;
            return runExperiment(o, *door.log);
          }};
}

}  // namespace afford
