// Reading a YAML configuration strictly, key by key: each value's type and
// range checked, a key nobody reads refused (with the known key it is likely
// a typo of), every error a ConfigError naming the key. The run
// configuration (afford/config.hpp) and the experiment files
// (experiment/design/experiment_file.hpp) are read through it.
#pragma once
#include <yaml-cpp/yaml.h>

#include <array>
#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include "afford/config.hpp"

namespace afford {

// Letters added, dropped, changed or two neighbours swapped, from a to b (Damerau-Levenshtein, as an optimal
// string alignment): "stpes" is one from "steps".
std::size_t editDistance(const std::string& a, const std::string& b);
// Of `known`, the name closest to `name` by edit distance, if close enough to be a typo of it ("" if none).
std::string closestName(const std::string& name, const std::vector<std::string>& known);
// "motivation" + "leak" -> "motivation.leak" ("" + key -> key).
std::string joinKey(const std::string& path, const std::string& key);
// Throws ConfigError("config key 'KEY': WHAT"), its key() the key.
[[noreturn]] void failKey(const std::string& key, const std::string& what);
// A node as an error names it: "\"text\"", "a list", "a map", "nothing".
std::string describeNode(const YAML::Node& node);
// "unknown key", with the known key (of the map at `path`) it is probably a typo of.
std::string unknownKey(const std::string& path, const std::string& key, const std::vector<std::string>& known);
// The names of the .yaml files of config_dir/sub, sorted.
std::vector<std::string> yamlNames(const std::string& config_dir, const char* sub);

// A view of one YAML map that remembers which keys were read, so that
// finish() can refuse the ones nobody asked for (typos).
class ConfigReader {
 public:
  ConfigReader(YAML::Node node, std::string path);  // throws if the node is not a map

  YAML::Node raw(const std::string& key);  // the key's node; missing: an error
  bool has(const std::string& key) const;
  double number(const std::string& key, double lo, double hi);
  std::int64_t integer(const std::string& key, std::int64_t lo, std::int64_t hi);
  std::string text(const std::string& key);
  template <typename E, std::size_t N>
  E choice(const std::string& key, const std::array<Named<E>, N>& names) {
    const std::string s = text(key);
    std::string known;
    for (const auto& n : names) {
      if (s == n.name) return n.value;
      known += known.empty() ? n.name : std::string(", ") + n.name;
    }
    failKey(keyPath(key), "unknown value \"" + s + "\" (expected one of: " + known + ")");
  }
  ConfigReader map(const std::string& key) { return ConfigReader(raw(key), keyPath(key)); }
  std::string keyPath(const std::string& key) const { return joinKey(path_, key); }
  // Every key of the map was read, or the first one that was not is refused.
  void finish() const;
  // The keys this map may hold, said before any is read (a map read by hand, whose keys are read only when
  // present): a key not among them is refused now, with the one it is likely a typo of, rather than a key it
  // displaced reported missing.
  void expect(std::vector<std::string> keys);

  static double toNumber(const std::string& key, const YAML::Node& v);
  static double checkRange(const std::string& key, double v, double lo, double hi);

 private:
  YAML::Node node_;
  std::string path_;
  std::set<std::string> used_;
  std::vector<std::string> expected_;
};

// A list of exactly n numbers in [lo, hi].
std::vector<double> numberList(ConfigReader& r, const std::string& key, std::size_t n, double lo, double hi);

}  // namespace afford
