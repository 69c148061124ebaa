// The physical table's truth, kept per world configuration: each (object, action) affordance estimated by
// trials (processes/environment/table/truth.hpp) and stored as a JSON file named by everything that decides it
// (the table section, the seed, the trials, the objects, this build's programs and MuJoCo's release), so that
// `afford world truth` and a table experiment estimate it once and read it after.
#pragma once
#include <yaml-cpp/yaml.h>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "afford/config.hpp"

namespace afford {

struct TruthRequest {
  std::string experiment;
  std::int64_t seed = 1;
  int trials = 0;            // 0: table.truth.trials
  std::vector<int> objects;  // indices; empty: every object
  std::string out;           // the folder of the stored tables
  bool fresh = false;        // estimate again though the folder has the table
  std::string code;          // this build's programs (codeFingerprint): a primitive changed is another table
};

struct StoredTruth {
  nlohmann::json rows;  // [{object, push: {successes, trials, rate, low, high}, carry: ..., ...}]
  std::string file;
  bool estimated = false;  // false: read from the file
};

// `node`: the experiment's effective configuration (effectiveConfig), `config` its parse. `log_warning` is told
// of a stored file it does not read; `progress` of each finished (object, action) while estimating, and may
// throw to stop (nothing is written then).
StoredTruth storedTruth(const YAML::Node& node, const RunConfig& config, const TruthRequest& request,
                        const std::function<void(const std::string&)>& log_warning,
                        const std::function<void(int object, int action)>& progress = {});

// The setting that gives a run its truth: table.objects as configured, each with `affordance` [push, carry,
// topple, roll] the stored rates (every object's row must be in `rows`).
std::string truthSetting(const YAML::Node& node, const nlohmann::json& rows);

}  // namespace afford
