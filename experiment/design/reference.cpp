#include "experiment/design/reference.hpp"

#include <sstream>

#include "afford/config.hpp"

namespace afford {

Reference::Reference(const std::string& config_dir) : path_(config_dir + "/reference.yaml") {
  try {
    root_ = YAML::LoadFile(path_);
  } catch (const YAML::Exception& e) {
    throw ConfigError(path_ + ": cannot be read (" + e.what() +
                      "): it holds the paper's numbers that results are shown beside");
  }
  if (!root_.IsMap()) throw ConfigError(path_ + ": expected a map of entries (base:, base_extrinsic:, ...)");
}

YAML::Node Reference::entry(const std::string& key) const { return root_[key]; }

namespace {
template <typename T>
T as(const std::string& path, const YAML::Node& node, const std::string& key_path, const char* kind) {
  try {
    if (!node) throw YAML::Exception(YAML::Mark::null_mark(), "missing");
    return node.as<T>();
  } catch (const YAML::Exception& e) {
    throw ConfigError(path + ": key " + key_path + ": expected " + kind + " (" + e.msg + ")");
  }
}
}  // namespace

double Reference::number(const YAML::Node& node, const std::string& key_path) const {
  return as<double>(path_, node, key_path, "a number");
}

std::string Reference::text(const YAML::Node& node, const std::string& key_path) const {
  return as<std::string>(path_, node, key_path, "a string");
}

std::vector<double> Reference::numbers(const YAML::Node& node, const std::string& key_path) const {
  return as<std::vector<double>>(path_, node, key_path, "a list of numbers");
}

double Reference::required(const std::string& key_path) const {
  YAML::Node node = root_;
  std::stringstream ss(key_path);
  for (std::string part; std::getline(ss, part, '.');) {
    const YAML::Node& here = node;
    if (!here.IsMap() || !here[part]) throw ConfigError(path_ + ": key " + key_path + " is missing");
    node.reset(here[part]);  // rebinds (assignment would overwrite the content)
  }
  return number(node, key_path);
}

}  // namespace afford
