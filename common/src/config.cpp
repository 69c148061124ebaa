#include "afford/config.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <deque>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>

#include "afford/image.hpp"
#include "afford/migrations.hpp"
#include "afford/yaml_reader.hpp"

namespace afford {
namespace {
// The keys the declaration cannot spell one by one (lists of maps), read by hand (below).
void readObjects(ConfigReader& w, WorldConfig& world);
void readTableObjects(ConfigReader& t, table::TableSpec& spec);
void readTriple(ConfigReader& r, const char* key, double* out, double lo, double hi);
void readScenario(ConfigReader& e, RunConfig& c);
}  // namespace
}  // namespace afford

#include "config_keys.hpp"

namespace afford {

namespace {

// A component's kind (motivation.kind, predictors.affordance.kind): a name a process's registry knows.
std::string componentKind(ConfigReader& r, const std::string& key) {
  const std::string kind = r.text(key);
  if (kind.empty()) failKey(r.keyPath(key), "is empty");
  for (char ch : kind)
    if (!((ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9') || ch == '_' || ch == '-') || kind.size() > 64)
      failKey(r.keyPath(key), "'" + kind + "' is not a name (lower-case letters, digits, '_', '-')");
  return kind;
}

ObjectSpec parseObject(const YAML::Node& node, const std::string& path, const WorldConfig& w) {
  ConfigReader r(node, path);
  r.expect({"name", "shape", "colour", "position", "appears_at", "affordance"});
  ObjectSpec o;
  o.name = r.text("name");
  o.shape = r.choice("shape", kShapeNames);
  o.colour = r.choice("colour", kColourNames);
  const auto pos = numberList(r, "position", 2, w.table_min, w.table_max);
  o.x = pos[0];
  o.y = pos[1];
  o.appears_at = r.integer("appears_at", 0, 1'000'000'000);
  const auto aff = numberList(r, "affordance", kNumActions, 0.0, 1.0);
  std::copy(aff.begin(), aff.end(), o.affordance.begin());
  r.finish();
  return o;
}

// The world's layout: the objects present at the start may not overlap or
// touch (the eye would see one blob), and two objects of one look (shape and
// colour) must have one affordance row (the environment acts by look).
void checkWorldLayout(const WorldConfig& w) {
  const int size = w.size_px;
  std::vector<int> owner(static_cast<std::size_t>(size) * size, -1);
  for (std::size_t i = 0; i < w.objects.size(); ++i) {
    const ObjectSpec& o = w.objects[i];
    for (std::size_t j = 0; j < i; ++j) {
      const ObjectSpec& p = w.objects[j];
      if (o.shape == p.shape && o.colour == p.colour && o.affordance != p.affordance)
        failKey("world.objects[" + std::to_string(i) + "].affordance",
             "'" + o.name + "' looks like '" + p.name + "' (world.objects[" + std::to_string(j) +
                 "]), a " + toString(o.colour) + " " + toString(o.shape) +
                 ", but has another affordance row: the environment acts by look, so one look has one row");
    }
    if (o.appears_at != 0) continue;  // late objects are placed where they are free when they come
    for (const Pixel& px : shapePixels(o.shape, o.x, o.y, w))
      for (int dr = -1; dr <= 1; ++dr)
        for (int dc = -1; dc <= 1; ++dc) {
          const int r = px.row + dr, c = px.col + dc;
          if (r < 0 || c < 0 || r >= size || c >= size) continue;
          const int other = owner[static_cast<std::size_t>(r) * size + c];
          if (other >= 0 && other != static_cast<int>(i))
            failKey("world.objects[" + std::to_string(i) + "].position",
                 "'" + o.name + "' at (" + std::to_string(o.x) + ", " + std::to_string(o.y) + ") overlaps or touches '" +
                     w.objects[static_cast<std::size_t>(other)].name + "' (world.objects[" + std::to_string(other) +
                     "]): objects present together must be apart, or the eye sees them as one");
        }
    for (const Pixel& px : shapePixels(o.shape, o.x, o.y, w))
      if (px.row >= 0 && px.col >= 0 && px.row < size && px.col < size)
        owner[static_cast<std::size_t>(px.row) * size + px.col] = static_cast<int>(i);
  }
}

ObjectState parseState(ConfigReader& parent, const std::string& key, const WorldConfig& w) {
  ConfigReader r = parent.map(key);
  ObjectState s;
  s.colour = r.choice("colour", kColourNames);
  const auto pos = numberList(r, "position", 2, w.table_min, w.table_max);
  s.x = pos[0];
  s.y = pos[1];
  r.finish();
  return s;
}

// A table scenario's place of an object: where the camera's image shows it, in scene units (a pixel's column
// and row over the image's width; the table's region is checked with the table section, validateScenario).
ObjectState parseTablePlace(ConfigReader& parent, const std::string& key, const WorldConfig& w) {
  ConfigReader r = parent.map(key);
  ObjectState s;
  const auto pos = numberList(r, "position", 2, 0.0, 1.0);
  s.x = pos[0];
  s.y = pos[1];
  const double rows = static_cast<double>(w.rows()) / w.size_px;
  if (s.y > rows)
    failKey(r.keyPath("position"), "y " + std::to_string(s.y) + " is below the image (its rows end at " +
                                       std::to_string(rows) + " of its width)");
  r.finish();
  return s;
}

// What one key's range cannot say: how protocol keys bound each other.
void checkProtocol(const ProtocolConfig& c, const std::string& path) {
  const auto key = [&](const std::string& k) { return joinKey(path, k); };
  if (c.max_deferred < c.resend_batch)
    failKey(key("max_deferred"), "must be at least resend_batch (" + std::to_string(c.resend_batch) +
                                  "): a channel catching up defers up to a batch");
  if (c.close_timeout_ms <= c.stop_grace_ms)
    failKey(key("close_timeout_ms"), "must be longer than stop_grace_ms (the logger waits that long first)");
  if (c.limits.run_id_bytes > c.limits.name_bytes)
    failKey(key("limits.run_id_bytes"), "must be at most name_bytes (" + std::to_string(c.limits.name_bytes) + ")");
  const BusConfig& b = c.bus;
  if (b.queue_bytes < b.max_message_bytes)
    failKey(key("bus.queue_bytes"), "must be at least max_message_bytes (" + std::to_string(b.max_message_bytes) +
                                     "): a whole message must fit in it");
  if (b.fragment_bytes < b.max_message_bytes)
    failKey(key("bus.fragment_bytes"), "must be at least max_message_bytes (" + std::to_string(b.max_message_bytes) +
                                        "): one whole message is reassembled in it");
  // The largest message a limit allows must fit on the bus (its other fields take a few KB at most).
  const long largest_text = std::max<long>(c.limits.config_bytes, c.limits.text_bytes);
  if (largest_text + 64 * 1024 > b.max_message_bytes)
    failKey(key("bus.max_message_bytes"), "must exceed limits.config_bytes and limits.text_bytes by 64 KiB (" +
                                           std::to_string(largest_text + 64 * 1024) +
                                           "): a RUN_CONFIG or STATUS at its limit must fit on the bus");
}

// A table world's run: the scene is the camera's image, the world's objects the table's (named, with the
// truth they are measured against when the configuration gives it), the scene set up anew as table.scene says.
void tableWorld(RunConfig& c) {
  if (!c.table.spec.camera.width) failKey("table", "missing: world.kind table needs the table section");
  if (c.table.spec.objects.empty()) failKey("table.objects", "missing: a table world needs objects");
  WorldConfig& w = c.world;
  w.size_px = c.table.spec.camera.width;
  w.height_px = c.table.spec.camera.height;
  w.reset_every = c.table.scene.reset_every;
  w.objects.clear();
  for (const table::ObjectSpec& t : c.table.spec.objects) {
    ObjectSpec o;
    o.name = t.name;
    std::copy(t.affordance.begin(), t.affordance.end(), o.affordance.begin());
    w.objects.push_back(o);
  }
}

// What one key's range cannot say: how a run's keys bound each other.
void checkRunConfig(const RunConfig& c) {
  if (c.eye.focus_side % 2 == 0) failKey("eye.focus_side", "must be odd (the gaze is the centre pixel)");
  if (c.motivation.revisit.enabled && c.motivation.kind != "paper")  // revisits are the paper motivation's
    failKey("motivation.revisit.enabled", "true needs motivation.kind paper (it is '" + c.motivation.kind + "')");
  if (c.predictors.memory.keep == MemoryKeep::Never && (c.predictors.replay.enabled || c.motivation.revisit.enabled))
    failKey("predictors.memory.keep",
         "never, but " +
             std::string(c.predictors.replay.enabled ? "predictors.replay.enabled" : "motivation.revisit.enabled") +
             " is true, which needs the memory");
  if ((c.phase == Phase::Goals) != (c.system == System::GOALS) && c.phase != Phase::Extrinsic)
    failKey("phase", std::string("the goals phase is system GOALS's, and GOALS learns in it (here phase ") +
                         nameOf(kPhaseNames, c.phase) + ", system " + toString(c.system) + ")");
  if (c.phase == Phase::Extrinsic && !c.scenario)
    failKey("extrinsic", "missing (an extrinsic run needs a checkpoint and a scenario)");
  checkProtocol(c.protocol, "protocol");
}

// The world's objects (world.objects): a list of maps the declaration cannot spell key by key.
void readTriple(ConfigReader& r, const char* key, double* out, double lo, double hi) {
  const auto v = numberList(r, key, 3, lo, hi);
  std::copy(v.begin(), v.end(), out);
}

// The table world's objects (table.objects): each a map of its kind's numbers.
void readTableObjects(ConfigReader& t, table::TableSpec& spec) {
  spec.objects.clear();
  if (!t.has("objects")) return;  // a grid experiment's run; a table world without objects is refused where it is built
  YAML::Node objs = t.raw("objects");
  const std::string key = t.keyPath("objects");
  if (!objs.IsSequence() || objs.size() == 0)
    failKey(key, "expected a non-empty list of objects, got " + describeNode(objs));
  for (std::size_t i = 0; i < objs.size(); ++i) {
    ConfigReader r(objs[i], key + "[" + std::to_string(i) + "]");
    r.expect({"name", "shape", "size", "lying", "mass", "friction", "torsional_friction", "rolling_friction", "colour",
              "affordance"});
    table::ObjectSpec o;
    o.name = r.text("name");
    o.shape = r.choice("shape", kTableShapeNames);
    const std::size_t n = o.shape == table::Shape::Box ? 3 : o.shape == table::Shape::Cylinder ? 2 : 1;
    o.size = numberList(r, "size", n, 0.001, 0.5);
    o.lying = r.has("lying") && r.choice("lying", kBoolNames);
    if (o.lying && o.shape != table::Shape::Cylinder) failKey(r.keyPath("lying"), "only a cylinder can be lying");
    o.mass = r.number("mass", 0.001, 100.0);
    o.friction = r.number("friction", 0.01, 10.0);
    o.torsional_friction = r.number("torsional_friction", 0.0, 1.0);
    o.rolling_friction = r.number("rolling_friction", 0.0, 1.0);
    readTriple(r, "colour", o.rgb.data(), 0, 1);
    if (r.has("affordance")) {
      const auto a = numberList(r, "affordance", o.affordance.size(), 0.0, 1.0);
      std::copy(a.begin(), a.end(), o.affordance.begin());
      o.has_affordance = true;
    }
    r.finish();
    for (const auto& before : spec.objects)
      if (before.name == o.name) failKey(r.keyPath("name"), "'" + o.name + "' names an earlier object too");
    spec.objects.push_back(std::move(o));
  }
}

void readObjects(ConfigReader& w, WorldConfig& world) {
  if (world.kind == WorldKind::Table) {
    if (w.has("objects"))
      failKey(w.keyPath("objects"), "is the paper's world's; the table world's objects are table.objects");
    return;
  }
  YAML::Node objs = w.raw("objects");
  if (!objs.IsSequence() || objs.size() == 0)
    failKey(w.keyPath("objects"), "expected a non-empty list of objects, got " + describeNode(objs));
  for (std::size_t i = 0; i < objs.size(); ++i)
    world.objects.push_back(parseObject(objs[i], w.keyPath("objects") + "[" + std::to_string(i) + "]", world));
  checkWorldLayout(world);
}

// An extrinsic test's scenario (extrinsic.scenario), of the run's world.
void readScenario(ConfigReader& e, RunConfig& c) {
  if (c.world.kind == WorldKind::Table) tableWorld(c);  // its objects' names (the table section is read by now)
  c.scenario = parseScenario(e.raw("scenario"), e.keyPath("scenario"), c.world);
}

// Reads a YAML tree through the declaration (config_keys.hpp): each key's
// type and range checked, unknown keys refused, each error naming its key.
class Parser {
 public:
  explicit Parser(ConfigReader& root) : stack_{&root} {}
  template <class F>
  void section(const char* key, F&& body) {
    ConfigReader r = top().map(key);
    stack_.push_back(&r);
    body();
    stack_.pop_back();
    r.finish();
  }
  template <class F>
  void given(const char* key, F&& body) {
    if (top().has(key)) body();
  }
  template <class T>
  void integer(const char* key, T& field, std::int64_t lo, std::int64_t hi, const char*) {
    field = static_cast<T>(top().integer(key, lo, hi));
  }
  void number(const char* key, double& field, double lo, double hi, const char*) { field = top().number(key, lo, hi); }
  void text(const char* key, std::string& field, const char*) { field = top().text(key); }
  void kind(const char* key, std::string& field, const char*) { field = componentKind(top(), key); }
  template <class E, std::size_t N>
  void choice(const char* key, E& field, const std::array<Named<E>, N>& names, const char*) {
    field = top().choice(key, names);
  }
  void pair(const char* key, double& a, double& b, double lo, double hi, const char*) {
    const auto v = numberList(top(), key, 2, lo, hi);
    a = v[0];
    b = v[1];
  }
  void interval(const char* key, double& a, double& b, double lo, double hi, const char* meaning) {
    pair(key, a, b, lo, hi, meaning);
    if (!(a < b)) failKey(top().keyPath(key), "expected [min, max] with min < max");
  }
  template <class F>
  void custom(const char*, const char*, F&& read, const char*) {
    read(top());
  }
  void from(KeyInfo::Origin) {}

 private:
  ConfigReader& top() { return *stack_.back(); }
  std::vector<ConfigReader*> stack_;
};

std::string rangeText(double lo, double hi) {
  std::ostringstream s;
  s << "[" << lo << ", " << hi << "]";
  return s.str();
}

// Lists the keys of the declaration: path, type and range, origin, meaning.
class Describer {
 public:
  std::vector<KeyInfo> keys;
  template <class F>
  void section(const char* key, F&& body) {
    path_.push_back(key);
    body();
    path_.pop_back();
  }
  template <class F>
  void given(const char*, F&& body) {
    body();
  }
  template <class T>
  void integer(const char* key, T&, std::int64_t lo, std::int64_t hi, const char* meaning) {
    add(key, "integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]", meaning);
  }
  void number(const char* key, double&, double lo, double hi, const char* meaning) {
    add(key, "number in " + rangeText(lo, hi), meaning);
  }
  void text(const char* key, std::string&, const char* meaning) { add(key, "text", meaning); }
  void kind(const char* key, std::string&, const char* meaning) { add(key, "a component's kind (a name)", meaning); }
  template <class E, std::size_t N>
  void choice(const char* key, E&, const std::array<Named<E>, N>& names, const char* meaning) {
    std::string t;
    for (const auto& n : names) t += (t.empty() ? "one of " : ", ") + std::string(n.name);
    add(key, t, meaning);
  }
  void pair(const char* key, double&, double&, double lo, double hi, const char* meaning) {
    add(key, "two numbers in " + rangeText(lo, hi), meaning);
  }
  void interval(const char* key, double&, double&, double lo, double hi, const char* meaning) {
    add(key, "[min, max] in " + rangeText(lo, hi) + ", min < max", meaning);
  }
  template <class F>
  void custom(const char* key, const char* type, F&&, const char* meaning) {
    add(key, type, meaning);
  }
  void from(KeyInfo::Origin origin) { origin_ = origin; }

 private:
  void add(const char* key, std::string type, const char* meaning) {
    std::string path;
    for (const auto& p : path_) path += p + ".";
    keys.push_back({path + key, std::move(type), meaning, origin_});
  }
  std::vector<std::string> path_;
  KeyInfo::Origin origin_ = KeyInfo::Origin::Defaults;
};

}  // namespace

Scenario parseScenario(const YAML::Node& node, const std::string& path, const WorldConfig& world) {
  ConfigReader r(node, path);
  Scenario s;
  s.name = r.text("name");
  if (r.has("description")) s.description = r.text("description");
  if (r.has("world")) s.world = r.choice("world", kWorldKindNames);
  if (s.world != world.kind)
    failKey(r.keyPath("world"), std::string("the scenario is of the ") + nameOf(kWorldKindNames, s.world) +
                                    " world" + (r.has("world") ? "" : " (it says no `world:`)") +
                                    ", and this run's world is " + nameOf(kWorldKindNames, world.kind) +
                                    ": a scenario names the world its objects are in");
  YAML::Node objs = r.raw("objects");
  const std::string key = r.keyPath("objects");
  if (!objs.IsSequence() || objs.size() == 0) failKey(key, "expected a non-empty list of objects, got " + describeNode(objs));
  for (std::size_t i = 0; i < objs.size(); ++i) {
    ConfigReader o(objs[i], key + "[" + std::to_string(i) + "]");
    ScenarioObject so;
    if (world.kind == WorldKind::Table) {
      so.object = o.text("object");
      std::string names;
      for (std::size_t k = 0; k < world.objects.size(); ++k) {
        if (world.objects[k].name == so.object) so.object_index = static_cast<int>(k);
        names += (k ? ", " : "") + world.objects[k].name;
      }
      if (so.object_index < 0) failKey(o.keyPath("object"), "'" + so.object + "' is none of table.objects (" + names + ")");
      for (std::size_t k = 0; k < s.objects.size(); ++k)
        if (s.objects[k].object_index == so.object_index)
          failKey(o.keyPath("object"), "'" + so.object + "' is objects[" + std::to_string(k) + "] already");
      so.initial = parseTablePlace(o, "initial", world);
      so.goal = parseTablePlace(o, "goal", world);
      so.value = o.has("value") ? o.number("value", 0.0, 1e6) : 1.0;
      o.finish();
      s.objects.push_back(so);
      continue;
    }
    so.shape = o.choice("shape", kShapeNames);
    so.initial = parseState(o, "initial", world);
    so.goal = parseState(o, "goal", world);
    so.value = o.has("value") ? o.number("value", 0.0, 1e6) : 1.0;
    so.actions = o.has("actions") ? static_cast<int>(o.integer("actions", 1, 8)) : 1;
    o.finish();
    s.objects.push_back(so);
  }
  r.finish();
  return s;
}

const char* toString(Shape s) { return nameOf(kShapeNames, s); }
const char* toString(Colour c) { return nameOf(kColourNames, c); }
const char* toString(System s) { return nameOf(kSystemNames, s); }
System parseSystem(const std::string& s) {
  for (const auto& n : kSystemNames)
    if (s == n.name) return n.value;
  throw ConfigError("unknown system \"" + s + "\" (expected FIX, IGN, IMP or GOALS)");
}
int colourChannel(Colour c) { return c == Colour::Red ? 0 : c == Colour::Green ? 1 : 2; }

ProtocolConfig parseProtocol(const YAML::Node& node, const std::string& path) {
  ConfigReader p(node, path);
  ProtocolConfig c;
  Parser v(p);
  declareProtocol(v, c);
  p.finish();
  checkProtocol(c, path);
  return c;
}

ProtocolConfig loadProtocol(const std::string& config_dir) {
  const std::filesystem::path file = std::filesystem::path(config_dir) / "defaults.yaml";
  YAML::Node root;
  try {
    root = YAML::LoadFile(file.string());
  } catch (const YAML::BadFile&) {
    throw ConfigError("cannot read config file " + file.string());
  } catch (const YAML::Exception& e) {
    throw ConfigError("config file " + file.string() + " is not valid YAML: " + e.what());
  }
  if (!root.IsMap() || !root["protocol"].IsDefined()) failKey("protocol", "missing in " + file.string());
  return parseProtocol(root["protocol"]);
}

RunConfig parseRunConfig(const YAML::Node& given) {
  // In this build's form: a configuration an earlier release wrote lacks keys added since, or spells renamed
  // ones as it did (config/migrations.yaml); each change is said once.
  const ConfigMigrations& migrations = configMigrations();
  YAML::Node root = migrations.added.empty() && migrations.renamed.empty() ? given : YAML::Clone(given);
  for (const std::string& line : upgradeConfig(root, migrations)) {
    static std::mutex mutex;
    static std::set<std::string> said;
    const std::lock_guard<std::mutex> lock(mutex);
    if (said.insert(line).second) spdlog::warn("configuration of an earlier release: {}", line);
  }
  ConfigReader r(root, "");
  RunConfig c;
  Parser v(r);
  declareRunConfig(v, c);
  r.finish();
  c.planner.attention = c.eye.attention;  // the eye and the planner read one key
  c.planner.world = c.world.kind;
  c.world.height_px = c.world.size_px;
  if (c.world.kind == WorldKind::Table) tableWorld(c);
  if (c.scenario) validateScenario(*c.scenario, c);  // the table's geometry needs the table section
  checkRunConfig(c);
  return c;
}

std::vector<KeyInfo> configKeys() {
  Describer d;
  RunConfig c;
  declareRunConfig(d, c);
  return d.keys;
}

std::string actionsCheckpoint(const std::string& checkpoint, std::int64_t actions) {
  const std::filesystem::path p(checkpoint);
  return (p.parent_path() / (p.stem().string() + ".after-" + std::to_string(actions) + "-actions" + p.extension().string()))
      .string();
}

RunConfig parseRunConfigText(const std::string& yaml_text) {
  // Every node of a run parses the run's text, and in one process (memq,
  // replay) they do so in turn: the last few texts parsed are kept with their
  // configuration (a text that is refused is not kept, and is refused again).
  static std::mutex mutex;
  static std::deque<std::pair<std::string, RunConfig>> recent;
  constexpr std::size_t kKept = 8;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    for (const auto& [text, config] : recent)
      if (text == yaml_text) return config;
  }
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(std::string("config is not valid YAML: ") + e.what());
  }
  RunConfig config = parseRunConfig(root);
  config.text = yaml_text;
  const std::lock_guard<std::mutex> lock(mutex);
  recent.emplace_front(yaml_text, config);
  if (recent.size() > kKept) recent.pop_back();
  return config;
}

std::string emitYaml(const YAML::Node& node) {
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  out << node;
  return std::string(out.c_str()) + "\n";
}

}  // namespace afford
