#include "afford/migrations.hpp"

#include <array>
#include <cstdlib>
#include <filesystem>
#include <mutex>

#include "afford/config.hpp"
#include "afford/process_main.hpp"

namespace afford {
namespace {

std::vector<std::string> parts(const std::string& dotted) {
  std::vector<std::string> p;
  std::string::size_type from = 0;
  for (auto at = dotted.find('.'); ; at = dotted.find('.', from)) {
    p.push_back(dotted.substr(from, at == std::string::npos ? std::string::npos : at - from));
    if (at == std::string::npos) return p;
    from = at + 1;
  }
}

// The node at `dotted` in `root`, if every map on the way has it (nothing is created).
YAML::Node find(const YAML::Node& root, const std::string& dotted) {
  YAML::Node at;
  at.reset(root);
  for (const std::string& k : parts(dotted)) {
    const YAML::Node& map = at;
    if (!map.IsMap() || !map[k].IsDefined()) return YAML::Node(YAML::NodeType::Undefined);
    at.reset(map[k]);
  }
  return at;
}

// Sets `dotted` in `root` to `value`, making the maps on the way; false if something on the way is not a map.
bool put(YAML::Node& root, const std::string& dotted, const YAML::Node& value) {
  const std::vector<std::string> p = parts(dotted);
  YAML::Node at;
  at.reset(root);
  for (std::size_t i = 0; i + 1 < p.size(); ++i) {
    if (!at.IsMap() && at.IsDefined() && !at.IsNull()) return false;
    YAML::Node next = at[p[i]];
    at.reset(next);
  }
  if (at.IsDefined() && !at.IsNull() && !at.IsMap()) return false;
  at[p.back()] = value;
  return true;
}

void remove(YAML::Node& root, const std::string& dotted) {
  const std::vector<std::string> p = parts(dotted);
  YAML::Node at;
  at.reset(root);
  for (std::size_t i = 0; i + 1 < p.size(); ++i) {
    YAML::Node next = at[p[i]];
    at.reset(next);
  }
  at.remove(p.back());
}

std::string text(const YAML::Node& entry, const char* key, const std::string& where) {
  if (!entry.IsMap() || !entry[key] || !entry[key].IsScalar() || entry[key].Scalar().empty())
    throw ConfigError(where + ": needs " + key + " (a name)", key);
  return entry[key].Scalar();
}

}  // namespace

ConfigMigrations loadMigrations(const std::string& file) {
  ConfigMigrations m;
  YAML::Node root;
  try {
    root = YAML::LoadFile(file);
  } catch (const YAML::Exception& e) {
    throw ConfigError("config file " + file + " is not valid YAML: " + e.what());
  }
  if (!root.IsMap()) throw ConfigError(file + ": expected a map of `added` and `renamed`");
  for (const auto& kv : root) {
    const std::string section = kv.first.as<std::string>("");
    if (section != "added" && section != "renamed")
      throw ConfigError(file + ": unknown section '" + section + "' (expected added, renamed)", section);
    if (!kv.second.IsSequence() && !kv.second.IsNull())
      throw ConfigError(file + ": " + section + " is a list", section);
  }
  std::size_t i = 0;
  for (const YAML::Node& e : root["added"]) {
    const std::string where = file + ": added[" + std::to_string(i++) + "]";
    if (!e.IsMap() || !e["value"]) throw ConfigError(where + ": needs value", "value");
    m.added.push_back({text(e, "key", where), text(e, "release", where), YAML::Clone(e["value"])});
  }
  i = 0;
  for (const YAML::Node& e : root["renamed"]) {
    const std::string where = file + ": renamed[" + std::to_string(i++) + "]";
    m.renamed.push_back({text(e, "from", where), text(e, "to", where), text(e, "release", where)});
  }
  return m;
}

const ConfigMigrations& configMigrations() {
  static const ConfigMigrations table = [] {
    const std::string file = defaultConfigDir() + "/migrations.yaml";
    std::error_code ec;
    return std::filesystem::exists(file, ec) ? loadMigrations(file) : ConfigMigrations{};
  }();
  return table;
}

std::vector<std::string> upgradeConfig(YAML::Node& root, const ConfigMigrations& m) {
  std::vector<std::string> said;
  if (!root.IsMap()) return said;  // (the parser names what is wrong with it)
  for (const auto& r : m.renamed) {
    const YAML::Node old = find(root, r.from);
    if (!old.IsDefined() || find(root, r.to).IsDefined()) continue;
    const YAML::Node value = YAML::Clone(old);
    if (!put(root, r.to, value)) continue;
    remove(root, r.from);
    said.push_back(r.from + " is spelt " + r.to + " since " + r.release + ": read as " + r.to);
  }
  for (const auto& a : m.added) {
    if (find(root, a.key).IsDefined() || !put(root, a.key, YAML::Clone(a.value))) continue;
    std::string value = emitYaml(a.value).substr(0, 60);
    if (!value.empty() && value.back() == '\n') value.pop_back();  // (emitYaml ends a document with one)
    said.push_back(a.key + ": absent (written before " + a.release + "), read as " + value);
  }
  return said;
}

namespace {
std::array<long, 3> releaseNumbers(const std::string& v) {
  std::array<long, 3> n{0, 0, 0};
  std::size_t at = 0;
  for (long& part : n) {
    char* end = nullptr;
    part = std::strtol(v.c_str() + at, &end, 10);
    at = static_cast<std::size_t>(end - v.c_str());
    if (at >= v.size() || v[at] != '.') break;
    ++at;
  }
  return n;
}
}  // namespace

bool releaseBefore(const std::string& a, const std::string& b) { return releaseNumbers(a) < releaseNumbers(b); }

std::string configAsWrittenBy(const std::string& text, const std::string& release, const ConfigMigrations& m) {
  std::vector<const ConfigMigrations::Added*> later;
  for (const auto& a : m.added)
    if (releaseBefore(release, a.release)) later.push_back(&a);
  if (later.empty()) return text;
  YAML::Node root = YAML::Load(text);
  bool changed = false;
  for (const auto* a : later) {
    const YAML::Node now = find(root, a->key);
    if (!now.IsDefined() || emitYaml(now) != emitYaml(a->value)) continue;
    remove(root, a->key);
    changed = true;
  }
  return changed ? emitYaml(root) : text;
}

}  // namespace afford
