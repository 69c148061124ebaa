#include "afford/yaml_reader.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

namespace afford {

std::size_t editDistance(const std::string& a, const std::string& b) {
  // Damerau-Levenshtein (optimal string alignment): a letter added, dropped, changed, or two neighbours swapped
  // ("stpes" for "steps") each count one. Three rows: the one two back is the swap's.
  std::vector<std::size_t> before(b.size() + 1), last(b.size() + 1), row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) last[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      row[j] = std::min({last[j] + 1, row[j - 1] + 1, last[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) row[j] = std::min(row[j], before[j - 2] + 1);
    }
    std::swap(before, last);
    std::swap(last, row);
  }
  return last[b.size()];
}

std::string closestName(const std::string& name, const std::vector<std::string>& known) {
  // Close enough to be a typo: at most a third of the longer name's letters (1 to 3) ("colr" for "colour").
  if (name.size() > 200) return "";
  std::string best;
  std::size_t best_distance = 4;
  for (const auto& k : known) {
    if (k == name || k.size() > 200) continue;
    const std::size_t most = std::clamp<std::size_t>(std::max(name.size(), k.size()) / 3, 1, 3);
    const std::size_t d = editDistance(name, k);
    if (d <= most && d < best_distance) best = k, best_distance = d;
  }
  return best;
}

std::string joinKey(const std::string& path, const std::string& key) { return path.empty() ? key : path + "." + key; }

void failKey(const std::string& key, const std::string& what) {
  throw ConfigError("config key '" + key + "': " + what, key);
}

std::string describeNode(const YAML::Node& n) {
  if (!n.IsDefined() || n.IsNull()) return "nothing";
  if (n.IsScalar()) return "\"" + n.Scalar() + "\"";
  if (n.IsSequence()) return "a list";
  return "a map";
}

std::string unknownKey(const std::string& path, const std::string& key, const std::vector<std::string>& known) {
  const std::string near = closestName(key, known);
  return near.empty() ? "unknown key" : "unknown key; did you mean '" + joinKey(path, near) + "'?";
}

std::vector<std::string> yamlNames(const std::string& config_dir, const char* sub) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(std::filesystem::path(config_dir) / sub, ec))
    if (entry.path().extension() == ".yaml") names.push_back(entry.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

ConfigReader::ConfigReader(YAML::Node node, std::string path) : node_(std::move(node)), path_(std::move(path)) {
  if (!node_.IsMap()) failKey(path_.empty() ? "<root>" : path_, "expected a map, got " + describeNode(node_));
}

YAML::Node ConfigReader::raw(const std::string& key) {
  used_.insert(key);
  YAML::Node v = node_[key];
  if (!v.IsDefined() || v.IsNull()) {
    // A key nobody reads beside it is likelier the cause: a typo of this one, or of another of the map's.
    for (const auto& kv : node_) {
      const std::string given = kv.first.Scalar();
      if (used_.count(given) || (!expected_.empty() && std::count(expected_.begin(), expected_.end(), given))) continue;
      if (closestName(given, {key}) == key)
        failKey(keyPath(key), "missing; '" + given + "' is given: did you mean '" + keyPath(key) + "'?");
    }
    failKey(keyPath(key), "missing");
  }
  return v;
}

void ConfigReader::expect(std::vector<std::string> keys) {
  expected_ = std::move(keys);
  for (const auto& kv : node_)
    if (const std::string k = kv.first.Scalar(); !std::count(expected_.begin(), expected_.end(), k))
      failKey(keyPath(k), unknownKey(path_, k, expected_));
}

bool ConfigReader::has(const std::string& key) const { return node_[key].IsDefined() && !node_[key].IsNull(); }

double ConfigReader::number(const std::string& key, double lo, double hi) {
  return checkRange(keyPath(key), toNumber(keyPath(key), raw(key)), lo, hi);
}

std::int64_t ConfigReader::integer(const std::string& key, std::int64_t lo, std::int64_t hi) {
  const std::string k = keyPath(key);
  YAML::Node v = raw(key);
  std::int64_t out = 0;
  if (!v.IsScalar() || !YAML::convert<std::int64_t>::decode(v, out)) failKey(k, "expected an integer, got " + describeNode(v));
  if (out < lo || out > hi)
    failKey(k, "value " + std::to_string(out) + " is out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return out;
}

std::string ConfigReader::text(const std::string& key) {
  YAML::Node v = raw(key);
  if (!v.IsScalar()) failKey(keyPath(key), "expected a string, got " + describeNode(v));
  return v.Scalar();
}

void ConfigReader::finish() const {
  for (const auto& kv : node_) {
    const std::string k = kv.first.Scalar();
    if (!used_.count(k)) {
      std::vector<std::string> known(used_.begin(), used_.end());
      known.insert(known.end(), expected_.begin(), expected_.end());
      failKey(keyPath(k), unknownKey(path_, k, known));
    }
  }
}

double ConfigReader::toNumber(const std::string& key, const YAML::Node& v) {
  double out = 0;
  if (!v.IsScalar() || !YAML::convert<double>::decode(v, out)) failKey(key, "expected a number, got " + describeNode(v));
  if (!std::isfinite(out)) failKey(key, "expected a finite number, got " + describeNode(v));
  return out;
}

double ConfigReader::checkRange(const std::string& key, double v, double lo, double hi) {
  if (v < lo || v > hi) {
    std::ostringstream s;
    s << "value " << v << " is out of range [" << lo << ", " << hi << "]";
    failKey(key, s.str());
  }
  return v;
}

std::vector<double> numberList(ConfigReader& r, const std::string& key, std::size_t n, double lo, double hi) {
  YAML::Node v = r.raw(key);
  const std::string k = r.keyPath(key);
  if (!v.IsSequence() || v.size() != n)
    failKey(k, "expected a list of " + std::to_string(n) + " numbers, got " + describeNode(v) +
                   (v.IsSequence() ? " of " + std::to_string(v.size()) : ""));
  std::vector<double> out;
  for (std::size_t i = 0; i < n; ++i) {
    const std::string ki = k + "[" + std::to_string(i) + "]";
    out.push_back(ConfigReader::checkRange(ki, ConfigReader::toNumber(ki, v[i]), lo, hi));
  }
  return out;
}

}  // namespace afford
