#include "experiment/plan/sweep.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <filesystem>
#include <set>

#include "afford/checksum.hpp"
#include "afford/config.hpp"
#include "experiment/design/experiment_file.hpp"

namespace afford {
namespace fs = std::filesystem;

std::vector<std::string> sweepValues(const std::string& value) {
  std::vector<std::string> out;
  std::string cur;
  int depth = 0;
  char quote = 0;
  for (char c : value) {
    if (quote) {
      if (c == quote) quote = 0;
    } else if (c == '"' || c == '\'') {
      quote = c;
    } else if (c == '[' || c == '{') {
      ++depth;
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    } else if (c == ',' && depth == 0) {
      out.push_back(cur);
      cur.clear();
      continue;
    }
    cur += c;
  }
  out.push_back(cur);
  return out;
}

namespace {

// A folder name from a condition's name: letters, digits and . _ = , - kept.
std::string folderOf(const std::string& name) {
  std::string f;
  for (char c : name) f += std::isalnum(static_cast<unsigned char>(c)) || std::string("._=,-").find(c) != std::string::npos ? c : '_';
  // A file name holds at most 255 bytes: a long condition keeps its start and
  // a hash of the whole name (summary.json maps each condition to its folder).
  constexpr std::size_t kLongest = 160;
  if (f.size() > kLongest) {
    Fnv1a h;
    h.add(name.data(), name.size());
    f = f.substr(0, kLongest - 17) + "-" + h.hex();
  }
  return f;
}

void addKey(Sweep& s, const std::string& key, std::vector<std::string> values, const std::string& where) {
  for (const auto& [k, v] : s.keys)
    if (k == key) throw ConfigError(where + ": config key '" + key + "' is swept twice");
  for (const auto& v : values)
    if (v.empty()) throw ConfigError(where + ": config key '" + key + "': an empty value in the sweep");
  s.keys.emplace_back(key, std::move(values));
}

}  // namespace

Sweep planSweep(const std::vector<std::string>& settings, const std::string& sweep_file) {
  Sweep s;
  for (const auto& setting : settings) {
    const auto eq = setting.find('=');
    if (eq == std::string::npos) {  // effectiveConfig names it
      s.fixed.push_back(setting);
      continue;
    }
    std::vector<std::string> values = sweepValues(setting.substr(eq + 1));
    if (values.size() == 1)
      s.fixed.push_back(setting);
    else
      addKey(s, setting.substr(0, eq), std::move(values), "--set " + setting);
  }
  if (!sweep_file.empty()) {
    const YAML::Node doc = loadGivenYaml(sweep_file, "sweep file");
    if (!doc.IsMap())
      throw ConfigError("sweep file " + sweep_file + ": expected a map of config keys to lists of values "
                        "(e.g. motivation.leak: [0.1, 0.2])");
    for (const auto& kv : doc) {
      if (!kv.first.IsScalar())
        throw ConfigError("sweep file " + sweep_file + ": a key that is not a config key name (line " +
                          std::to_string(kv.first.Mark().line + 1) + ")");
      const std::string key = kv.first.Scalar();
      const YAML::Node& v = kv.second;
      std::vector<std::string> values;
      if (v.IsSequence()) {
        for (const auto& e : v) {
          if (e.IsScalar()) {
            values.push_back(e.Scalar());
          } else {
            YAML::Emitter em;
            em << YAML::Flow << e;
            values.push_back(em.c_str());
          }
        }
        if (values.empty()) throw ConfigError("sweep file " + sweep_file + ": config key '" + key + "': no values");
      } else if (v.IsScalar()) {
        values.push_back(v.Scalar());
      } else {
        throw ConfigError("sweep file " + sweep_file + ": config key '" + key + "': expected a list of values");
      }
      for (const auto& f : s.fixed)
        if (f.substr(0, f.find('=')) == key)
          throw ConfigError("sweep file " + sweep_file + ": config key '" + key + "' is also given by --set");
      if (values.size() == 1)
        s.fixed.push_back(key + "=" + values.front());
      else
        addKey(s, key, std::move(values), "sweep file " + sweep_file);
    }
  }
  for (const auto& f : s.fixed)
    for (const auto& [k, v] : s.keys)
      if (f.substr(0, f.find('=')) == k) throw ConfigError("--set: config key '" + k + "' is both swept and set");
  if (s.keys.empty()) return s;
  // The cross product, the last key varying fastest.
  std::vector<std::size_t> at(s.keys.size(), 0);
  std::set<std::string> folders;
  for (;;) {
    SweepCondition c;
    for (std::size_t i = 0; i < s.keys.size(); ++i) {
      const std::string kv = s.keys[i].first + "=" + s.keys[i].second[at[i]];
      c.settings.push_back(kv);
      c.name += (c.name.empty() ? "" : ",") + kv;
    }
    c.folder = folderOf(c.name);
    for (int k = 2; folders.count(c.folder); ++k) c.folder = folderOf(c.name) + "-" + std::to_string(k);
    folders.insert(c.folder);
    s.conditions.push_back(std::move(c));
    std::size_t i = s.keys.size();
    while (i > 0 && ++at[i - 1] == s.keys[i - 1].second.size()) at[--i] = 0;
    if (i == 0) break;
  }
  return s;
}

std::vector<Part> planParts(const PlanRequest& o, const std::string& out_dir, const Sweep& sweep) {
  std::vector<Part> parts;
  if (sweep.conditions.empty()) {
    Part p;
    p.request = o;
    p.request.settings = sweep.fixed;
    p.out_dir = out_dir;
    p.plan = planExperiment(p.request);
    parts.push_back(std::move(p));
    return parts;
  }
  std::set<std::string> ids;
  for (std::size_t k = 0; k < sweep.conditions.size(); ++k) {
    const SweepCondition& c = sweep.conditions[k];
    Part p;
    p.request = o;
    p.request.settings = sweep.fixed;
    p.request.settings.insert(p.request.settings.end(), c.settings.begin(), c.settings.end());
    p.request.run_prefix = o.run_prefix + "-c" + std::to_string(k);
    p.out_dir = (fs::path(out_dir) / "conditions" / c.folder).string();
    p.condition = c.name;
    p.condition_settings = c.settings;
    try {
      p.plan = planExperiment(p.request);
    } catch (const ConfigError& e) {
      throw ConfigError("sweep condition '" + c.name + "': " + e.what());
    }
    parts.push_back(std::move(p));
  }
  return parts;
}

std::vector<PlannedRun> concatRuns(const std::vector<std::vector<PlannedRun>>& parts, std::vector<std::size_t>& offsets) {
  std::vector<PlannedRun> all;
  offsets.clear();
  for (const auto& runs : parts) {
    offsets.push_back(all.size());
    for (PlannedRun r : runs) {
      r.index = all.size();
      all.push_back(std::move(r));
    }
  }
  return all;
}


}  // namespace afford
