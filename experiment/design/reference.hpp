// config/reference.yaml: the paper's published numbers, the definitions of its
// tables' thresholds, and the floors of this project's issues, shown beside
// our results (compared, never used in a run). A file that cannot be read, or
// a value of the wrong kind, is an error naming the file and the key.
#pragma once
#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

namespace afford {

class Reference {
 public:
  // Loads <config_dir>/reference.yaml; throws ConfigError naming it.
  explicit Reference(const std::string& config_dir);
  // The entry `key` (e.g. "base", "base_extrinsic"); an undefined node if absent.
  YAML::Node entry(const std::string& key) const;
  // Values under an entry; each throws ConfigError naming file and key path if the value is not of the kind.
  double number(const YAML::Node& node, const std::string& key_path) const;
  std::string text(const YAML::Node& node, const std::string& key_path) const;
  std::vector<double> numbers(const YAML::Node& node, const std::string& key_path) const;
  // A number that must be there: `key_path` from the root, e.g. "thresholds.table_metric.solved_share".
  double required(const std::string& key_path) const;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  YAML::Node root_;
};

}  // namespace afford
