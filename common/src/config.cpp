#include "afford/config.hpp"

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
#include "config_keys.hpp"

namespace afford {

std::string closestName(const std::string& name, const std::vector<std::string>& known) {
  // Levenshtein distance, one row at a time; close enough: at most a third of the name's letters (1 to 3).
  const auto distance = [](const std::string& a, const std::string& b) {
    std::vector<std::size_t> row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
      std::size_t diagonal = row[0];
      row[0] = i;
      for (std::size_t j = 1; j <= b.size(); ++j) {
        const std::size_t up = row[j];
        row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
        diagonal = up;
      }
    }
    return row[b.size()];
  };
  if (name.size() > 200) return "";
  const std::size_t most = std::clamp<std::size_t>(name.size() / 3, 1, 3);
  std::string best;
  std::size_t best_distance = most + 1;
  for (const auto& k : known) {
    if (k == name || k.size() > 200) continue;
    const std::size_t d = distance(name, k);
    if (d < best_distance) best = k, best_distance = d;
  }
  return best;
}

namespace {

std::string join(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

[[noreturn]] void fail(const std::string& key, const std::string& what) {
  throw ConfigError("config key '" + key + "': " + what, key);
}

// "unknown key", and the known key (of the map at `path`) it is probably a typo of.
std::string unknownKey(const std::string& path, const std::string& key, const std::vector<std::string>& known) {
  const std::string near = closestName(key, known);
  return near.empty() ? "unknown key" : "unknown key; did you mean '" + (path.empty() ? near : path + "." + near) + "'?";
}

std::string describe(const YAML::Node& n) {
  if (!n.IsDefined() || n.IsNull()) return "nothing";
  if (n.IsScalar()) return "\"" + n.Scalar() + "\"";
  if (n.IsSequence()) return "a list";
  return "a map";
}

// A view of one YAML map that remembers which keys were read, so that
// finish() can reject the ones nobody asked for (typos).
class Reader {
 public:
  Reader(YAML::Node node, std::string path) : node_(std::move(node)), path_(std::move(path)) {
    if (!node_.IsMap()) fail(path_.empty() ? "<root>" : path_, "expected a map, got " + describe(node_));
  }

  YAML::Node raw(const std::string& key) {
    used_.insert(key);
    YAML::Node v = node_[key];
    if (!v.IsDefined() || v.IsNull()) fail(join(path_, key), "missing");
    return v;
  }
  bool has(const std::string& key) const { return node_[key].IsDefined() && !node_[key].IsNull(); }

  double number(const std::string& key, double lo, double hi) {
    return checkRange(join(path_, key), toNumber(join(path_, key), raw(key)), lo, hi);
  }
  std::int64_t integer(const std::string& key, std::int64_t lo, std::int64_t hi) {
    const std::string k = join(path_, key);
    YAML::Node v = raw(key);
    std::int64_t out = 0;
    if (!v.IsScalar() || !YAML::convert<std::int64_t>::decode(v, out))
      fail(k, "expected an integer, got " + describe(v));
    if (out < lo || out > hi)
      fail(k, "value " + std::to_string(out) + " is out of range [" + std::to_string(lo) + ", " +
                  std::to_string(hi) + "]");
    return out;
  }
  std::string text(const std::string& key) {
    YAML::Node v = raw(key);
    if (!v.IsScalar()) fail(join(path_, key), "expected a string, got " + describe(v));
    return v.Scalar();
  }
  template <typename E, std::size_t N>
  E choice(const std::string& key, const std::array<Named<E>, N>& names) {
    const std::string s = text(key);
    std::string known;
    for (const auto& n : names) {
      if (s == n.name) return n.value;
      known += known.empty() ? n.name : std::string(", ") + n.name;
    }
    fail(join(path_, key), "unknown value \"" + s + "\" (expected one of: " + known + ")");
  }
  Reader map(const std::string& key) { return Reader(raw(key), join(path_, key)); }
  std::string keyPath(const std::string& key) const { return join(path_, key); }

  void finish() const {
    for (const auto& kv : node_) {
      const std::string k = kv.first.Scalar();
      if (!used_.count(k)) fail(join(path_, k), unknownKey(path_, k, {used_.begin(), used_.end()}));
    }
  }

  static double toNumber(const std::string& key, const YAML::Node& v) {
    double out = 0;
    if (!v.IsScalar() || !YAML::convert<double>::decode(v, out))
      fail(key, "expected a number, got " + describe(v));
    if (!std::isfinite(out)) fail(key, "expected a finite number, got " + describe(v));
    return out;
  }
  static double checkRange(const std::string& key, double v, double lo, double hi) {
    if (v < lo || v > hi) {
      std::ostringstream s;
      s << "value " << v << " is out of range [" << lo << ", " << hi << "]";
      fail(key, s.str());
    }
    return v;
  }

 private:
  YAML::Node node_;
  std::string path_;
  std::set<std::string> used_;
};

// A component's kind (motivation.kind, predictors.affordance.kind): a name a process's registry knows.
std::string componentKind(Reader& r, const std::string& key) {
  const std::string kind = r.text(key);
  if (kind.empty()) fail(r.keyPath(key), "is empty");
  for (char ch : kind)
    if (!((ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9') || ch == '_' || ch == '-') || kind.size() > 64)
      fail(r.keyPath(key), "'" + kind + "' is not a name (lower-case letters, digits, '_', '-')");
  return kind;
}

std::vector<double> numberList(Reader& r, const std::string& key, std::size_t n, double lo, double hi) {
  YAML::Node v = r.raw(key);
  const std::string k = r.keyPath(key);
  if (!v.IsSequence() || v.size() != n)
    fail(k, "expected a list of " + std::to_string(n) + " numbers, got " + describe(v) +
                (v.IsSequence() ? " of " + std::to_string(v.size()) : ""));
  std::vector<double> out;
  for (std::size_t i = 0; i < n; ++i) {
    const std::string ki = k + "[" + std::to_string(i) + "]";
    out.push_back(Reader::checkRange(ki, Reader::toNumber(ki, v[i]), lo, hi));
  }
  return out;
}

ObjectSpec parseObject(const YAML::Node& node, const std::string& path, const WorldConfig& w) {
  Reader r(node, path);
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
        fail("world.objects[" + std::to_string(i) + "].affordance",
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
            fail("world.objects[" + std::to_string(i) + "].position",
                 "'" + o.name + "' at (" + std::to_string(o.x) + ", " + std::to_string(o.y) + ") overlaps or touches '" +
                     w.objects[static_cast<std::size_t>(other)].name + "' (world.objects[" + std::to_string(other) +
                     "]): objects present together must be apart, or the eye sees them as one");
        }
    for (const Pixel& px : shapePixels(o.shape, o.x, o.y, w))
      if (px.row >= 0 && px.col >= 0 && px.row < size && px.col < size)
        owner[static_cast<std::size_t>(px.row) * size + px.col] = static_cast<int>(i);
  }
}

// Names of the .yaml files of config_dir/sub, sorted.
std::vector<std::string> yamlNames(const std::string& config_dir, const char* sub) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(std::filesystem::path(config_dir) / sub, ec))
    if (entry.path().extension() == ".yaml") names.push_back(entry.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

ObjectState parseState(Reader& parent, const std::string& key, const WorldConfig& w) {
  Reader r = parent.map(key);
  ObjectState s;
  s.colour = r.choice("colour", kColourNames);
  const auto pos = numberList(r, "position", 2, w.table_min, w.table_max);
  s.x = pos[0];
  s.y = pos[1];
  r.finish();
  return s;
}

// What one key's range cannot say: how protocol keys bound each other.
void checkProtocol(const ProtocolConfig& c, const std::string& path) {
  const auto key = [&](const std::string& k) { return join(path, k); };
  if (c.max_deferred < c.resend_batch)
    fail(key("max_deferred"), "must be at least resend_batch (" + std::to_string(c.resend_batch) +
                                  "): a channel catching up defers up to a batch");
  if (c.close_timeout_ms <= c.stop_grace_ms)
    fail(key("close_timeout_ms"), "must be longer than stop_grace_ms (the logger waits that long first)");
  if (c.limits.run_id_bytes > c.limits.name_bytes)
    fail(key("limits.run_id_bytes"), "must be at most name_bytes (" + std::to_string(c.limits.name_bytes) + ")");
  const BusConfig& b = c.bus;
  if (b.queue_bytes < b.max_message_bytes)
    fail(key("bus.queue_bytes"), "must be at least max_message_bytes (" + std::to_string(b.max_message_bytes) +
                                     "): a whole message must fit in it");
  if (b.fragment_bytes < b.max_message_bytes)
    fail(key("bus.fragment_bytes"), "must be at least max_message_bytes (" + std::to_string(b.max_message_bytes) +
                                        "): one whole message is reassembled in it");
  // The largest message a limit allows must fit on the bus (its other fields take a few KB at most).
  const long largest_text = std::max<long>(c.limits.config_bytes, c.limits.text_bytes);
  if (largest_text + 64 * 1024 > b.max_message_bytes)
    fail(key("bus.max_message_bytes"), "must exceed limits.config_bytes and limits.text_bytes by 64 KiB (" +
                                           std::to_string(largest_text + 64 * 1024) +
                                           "): a RUN_CONFIG or STATUS at its limit must fit on the bus");
}

// What one key's range cannot say: how a run's keys bound each other.
void checkRunConfig(const RunConfig& c) {
  if (c.eye.focus_side % 2 == 0) fail("eye.focus_side", "must be odd (the gaze is the centre pixel)");
  if (c.motivation.revisit.enabled && c.motivation.kind != "paper")  // revisits are the paper motivation's
    fail("motivation.revisit.enabled", "true needs motivation.kind paper (it is '" + c.motivation.kind + "')");
  if (c.predictors.memory.keep == MemoryKeep::Never && (c.predictors.replay.enabled || c.motivation.revisit.enabled))
    fail("predictors.memory.keep",
         "never, but " +
             std::string(c.predictors.replay.enabled ? "predictors.replay.enabled" : "motivation.revisit.enabled") +
             " is true, which needs the memory");
  if (c.phase == Phase::Extrinsic && !c.scenario)
    fail("extrinsic", "missing (an extrinsic run needs a checkpoint and a scenario)");
  checkProtocol(c.protocol, "protocol");
}

// The world's objects (world.objects): a list of maps the declaration cannot spell key by key.
void readObjects(Reader& w, WorldConfig& world) {
  YAML::Node objs = w.raw("objects");
  if (!objs.IsSequence() || objs.size() == 0)
    fail(w.keyPath("objects"), "expected a non-empty list of objects, got " + describe(objs));
  for (std::size_t i = 0; i < objs.size(); ++i)
    world.objects.push_back(parseObject(objs[i], w.keyPath("objects") + "[" + std::to_string(i) + "]", world));
  checkWorldLayout(world);
}

// An extrinsic test's scenario (extrinsic.scenario), of the run's world.
void readScenario(Reader& e, RunConfig& c) {
  c.scenario = parseScenario(e.raw("scenario"), e.keyPath("scenario"), c.world);
  validateScenario(*c.scenario, c.world);
}

// Reads a YAML tree through the declaration (config_keys.hpp): each key's
// type and range checked, unknown keys refused, each error naming its key.
class Parser {
 public:
  explicit Parser(Reader& root) : stack_{&root} {}
  template <class F>
  void section(const char* key, F&& body) {
    Reader r = top().map(key);
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
    if (!(a < b)) fail(top().keyPath(key), "expected [min, max] with min < max");
  }
  template <class F>
  void custom(const char*, const char*, F&& read, const char*) {
    read(top());
  }
  void from(KeyInfo::Origin) {}

 private:
  Reader& top() { return *stack_.back(); }
  std::vector<Reader*> stack_;
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
  Reader r(node, path);
  Scenario s;
  s.name = r.text("name");
  if (r.has("description")) s.description = r.text("description");
  YAML::Node objs = r.raw("objects");
  const std::string key = r.keyPath("objects");
  if (!objs.IsSequence() || objs.size() == 0) fail(key, "expected a non-empty list of objects, got " + describe(objs));
  for (std::size_t i = 0; i < objs.size(); ++i) {
    Reader o(objs[i], key + "[" + std::to_string(i) + "]");
    ScenarioObject so;
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

std::vector<std::string> listScenarios(const std::string& config_dir) { return yamlNames(config_dir, "scenarios"); }

const char* toString(Shape s) { return nameOf(kShapeNames, s); }
const char* toString(Colour c) { return nameOf(kColourNames, c); }
const char* toString(System s) { return nameOf(kSystemNames, s); }
System parseSystem(const std::string& s) {
  for (const auto& n : kSystemNames)
    if (s == n.name) return n.value;
  throw ConfigError("unknown system \"" + s + "\" (expected FIX, IGN or IMP)");
}
std::vector<std::string> parseSystems(const std::vector<std::string>& given, const std::string& option) {
  std::vector<std::string> out;
  const auto add = [&](const std::string& name) {
    if (std::find(out.begin(), out.end(), name) == out.end()) out.push_back(name);
  };
  for (const std::string& g : given) {
    std::stringstream items(g);
    std::string item;
    bool any = false;
    while (std::getline(items, item, ',')) {
      any = true;
      if (item == "all") {
        for (const char* s : {"FIX", "IGN", "IMP"}) add(s);
        continue;
      }
      try {
        add(toString(parseSystem(item)));
      } catch (const ConfigError&) {
        std::string upper = item;
        for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
        const bool cased = upper == "FIX" || upper == "IGN" || upper == "IMP";
        throw ConfigError(option + ": unknown system \"" + item + "\" in \"" + g + "\"" +
                          (cased ? "; did you mean " + upper + "? (systems are written in capitals)" : "") +
                          " (FIX, IGN, IMP, all, or a list: FIX,IMP)");
      }
    }
    if (!any) throw ConfigError(option + ": empty (FIX, IGN, IMP, all, or a list: FIX,IMP)");
  }
  return out;
}
int colourChannel(Colour c) { return c == Colour::Red ? 0 : c == Colour::Green ? 1 : 2; }

ProtocolConfig parseProtocol(const YAML::Node& node, const std::string& path) {
  Reader p(node, path);
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
  if (!root.IsMap() || !root["protocol"].IsDefined()) fail("protocol", "missing in " + file.string());
  return parseProtocol(root["protocol"]);
}

RunConfig parseRunConfig(const YAML::Node& root) {
  Reader r(root, "");
  RunConfig c;
  Parser v(r);
  declareRunConfig(v, c);
  r.finish();
  c.planner.attention = c.eye.attention;  // the eye and the planner read one key
  checkRunConfig(c);
  return c;
}

std::vector<KeyInfo> configKeys() {
  Describer d;
  RunConfig c;
  declareRunConfig(d, c);
  return d.keys;
}

namespace {

// Each key's value and comment as config/defaults.yaml spells them (its
// first line): "steps: 6000  # paper 3.1.1 ..." gives run.steps -> {6000, paper 3.1.1 ...}.
struct DefaultLine {
  std::string value, comment;
};
std::map<std::string, DefaultLine> defaultLines(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw ConfigError("cannot read config file " + file.string());
  std::map<std::string, DefaultLine> out;
  std::vector<std::pair<std::size_t, std::string>> open;  // the sections the line is in: indentation, key
  const auto trim = [](std::string t) {
    t.erase(0, t.find_first_not_of(" \t"));
    t.erase(t.find_last_not_of(" \t") + 1);
    return t;
  };
  for (std::string line; std::getline(in, line);) {
    const std::size_t indent = line.find_first_not_of(' ');
    if (indent == std::string::npos || line[indent] == '#') continue;
    const std::size_t colon = line.find(':', indent);
    if (colon == std::string::npos) continue;
    while (!open.empty() && open.back().first >= indent) open.pop_back();
    std::string path;
    for (const auto& [i, k] : open) path += k + ".";
    path += line.substr(indent, colon - indent);
    // The comment begins at the first '#' outside quotes.
    std::size_t hash = std::string::npos;
    bool quoted = false;
    for (std::size_t i = colon + 1; i < line.size() && hash == std::string::npos; ++i) {
      if (line[i] == '"') quoted = !quoted;
      if (line[i] == '#' && !quoted) hash = i;
    }
    const std::string value = trim(line.substr(colon + 1, hash == std::string::npos ? std::string::npos : hash - colon - 1));
    const std::string comment = hash == std::string::npos ? "" : trim(line.substr(hash + 1));
    if (value.empty())
      open.emplace_back(indent, line.substr(indent, colon - indent));
    else
      out[path] = {value, comment};
  }
  return out;
}

std::string cell(const std::string& text) {
  std::string out;
  for (char ch : text) out += ch == '|' ? std::string("\\|") : std::string(1, ch);
  return out;
}

// Every scalar of a tree, by its dotted key ("motivation.leak" -> "0.3");
// lists and the keys in `skip` (and below them) are left out.
void flatten(const YAML::Node& node, const std::string& path, const std::set<std::string>& skip,
             std::map<std::string, std::string>& out) {
  if (skip.count(path)) return;
  if (node.IsScalar()) out[path] = node.Scalar();
  if (!node.IsMap()) return;
  for (const auto& kv : node) flatten(kv.second, join(path, kv.first.Scalar()), skip, out);
}

// The values the experiment files (and their systems' blocks) give in place
// of defaults.yaml's, as a table: key, default, and each other value with
// where it is set ("base: IGN" for one system; an experiment alone for all).
std::string overridesMarkdown(const std::string& config_dir, const std::map<std::string, DefaultLine>& lines) {
  // The runner's keys and the world's objects differ by their nature.
  const std::set<std::string> skip{"experiment", "system", "seed", "run", "world.objects"};
  std::map<std::string, std::map<std::string, std::map<std::string, std::vector<std::string>>>> by_key;  // key, value, experiment, systems
  for (const std::string& name : listExperiments(config_dir))
    for (const auto& sys : kSystemNames) {
      std::map<std::string, std::string> flat;
      flatten(effectiveConfig(config_dir, RunRequest{name, sys.value, 1, std::nullopt, {}}), "", skip, flat);
      for (const auto& [key, value] : flat) {
        const auto d = lines.find(key);
        if (d != lines.end() && YAML::Load(d->second.value).Scalar() != value) by_key[key][value][name].push_back(sys.name);
      }
    }
  std::ostringstream out;
  out << "| key | default | elsewhere |\n|---|---|---|\n";
  for (const auto& [key, values] : by_key) {
    std::string elsewhere;
    for (const auto& [value, experiments] : values) {
      std::string where;
      for (const auto& [name, systems] : experiments) {
        std::string who = name;
        if (systems.size() < kSystemNames.size()) {
          who += ":";
          for (const auto& s : systems) who += " " + s;
        }
        where += (where.empty() ? "" : ", ") + who;
      }
      elsewhere += (elsewhere.empty() ? "" : "; ") + value + " (" + where + ")";
    }
    out << "| `" << key << "` | " << cell(lines.at(key).value) << " | " << cell(elsewhere) << " |\n";
  }
  return out.str();
}

}  // namespace

std::string keysMarkdown(const std::string& config_dir) {
  const auto lines = defaultLines(std::filesystem::path(config_dir) / "defaults.yaml");
  std::ostringstream run, protocol;
  run << "| key | type | default | source | meaning |\n|---|---|---|---|---|\n";
  protocol << "| key | type | default | meaning |\n|---|---|---|---|\n";
  for (const KeyInfo& k : configKeys()) {
    std::string value = k.origin == KeyInfo::Origin::Runner ? "set by the runner" : "per experiment";
    std::string source;
    if (k.origin == KeyInfo::Origin::Defaults) {
      const auto line = lines.find(k.key);
      if (line == lines.end()) throw ConfigError("config key '" + k.key + "': missing in " + config_dir + "/defaults.yaml");
      value = line->second.value;
      source = line->second.comment.substr(0, line->second.comment.find(':'));
    }
    if (k.key.rfind("protocol.", 0) == 0)
      protocol << "| `" << k.key << "` | " << cell(k.type) << " | " << cell(value) << " | " << cell(k.meaning) << " |\n";
    else
      run << "| `" << k.key << "` | " << cell(k.type) << " | " << cell(value) << " | " << cell(source) << " | "
          << cell(k.meaning) << " |\n";
  }
  return run.str() + "\n" + protocol.str() +
         "\nThe values the experiment files give in place of the defaults (each "
         "experiment's file names their sources); `name: FIX` is one system's block, "
         "a name alone holds for every system:\n\n" +
         overridesMarkdown(config_dir, lines);
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

void mergeInto(YAML::Node base, const YAML::Node& over) {
  if (!over.IsMap()) return;
  for (const auto& kv : over) {
    const std::string key = kv.first.Scalar();
    if (kv.second.IsMap() && base[key].IsMap()) {
      mergeInto(base[key], kv.second);
    } else {
      base[key] = YAML::Clone(kv.second);
    }
  }
}

std::vector<std::string> listExperiments(const std::string& config_dir) { return yamlNames(config_dir, "experiments"); }

namespace {
YAML::Node loadFile(const std::filesystem::path& file) {
  // Planning reads the same few files for each of thousands of runs: a file is
  // parsed again only when its size or time of change differs from the last.
  struct Parsed {
    std::uintmax_t size;
    std::filesystem::file_time_type mtime;
    YAML::Node node;
  };
  static std::mutex mutex;
  static std::map<std::string, Parsed> parsed;
  std::error_code ec;
  const auto size = std::filesystem::file_size(file, ec);
  const auto mtime = ec ? std::filesystem::file_time_type() : std::filesystem::last_write_time(file, ec);
  if (!ec) {
    const std::lock_guard<std::mutex> lock(mutex);
    if (auto it = parsed.find(file.string()); it != parsed.end() && it->second.size == size && it->second.mtime == mtime)
      return YAML::Clone(it->second.node);
  }
  try {
    YAML::Node node = YAML::LoadFile(file.string());
    if (!ec) {
      const std::lock_guard<std::mutex> lock(mutex);
      parsed[file.string()] = Parsed{size, mtime, YAML::Clone(node)};
    }
    return node;
  } catch (const YAML::BadFile&) {
    throw ConfigError("cannot read config file " + file.string());
  } catch (const YAML::Exception& e) {
    throw ConfigError("config file " + file.string() + " is not valid YAML: " + e.what());
  }
}

// config_dir/<folder>/<name>.yaml, or a ConfigError listing the names known there.
std::filesystem::path namedFile(const std::string& config_dir, const char* folder, const char* kind,
                                const std::string& name) {
  const auto known = yamlNames(config_dir, folder);
  if (std::find(known.begin(), known.end(), name) == known.end()) {
    std::string list;
    for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
    const std::string near = closestName(name, known);
    throw ConfigError(std::string("unknown ") + kind + " \"" + name + "\"" +
                      (near.empty() ? "" : "; did you mean \"" + near + "\"?") + " (known in " + config_dir + "/" +
                      folder + ": " + list + ")");
  }
  return std::filesystem::path(config_dir) / folder / (name + ".yaml");
}
}  // namespace

Scenario loadScenario(const std::string& config_dir, const std::string& name, const WorldConfig& world) {
  const auto file = namedFile(config_dir, "scenarios", "scenario", name);
  Scenario s = parseScenario(loadFile(file), "", world);
  validateScenario(s, world);
  return s;
}

namespace {
ExtrinsicDesign parseDesign(const YAML::Node& node, const std::string& file) {
  Reader r(node, "extrinsic");
  ExtrinsicDesign d;
  if (r.has("generate")) {
    Reader g = r.map("generate");
    GenerateDesign gen;
    auto counts = [&](const char* key) {
      std::vector<int> out;
      const YAML::Node n = g.raw(key);
      const std::string path = g.keyPath(key);
      if (n.IsScalar())
        out.push_back(static_cast<int>(g.integer(key, 1, 256)));
      else if (n.IsSequence() && n.size() > 0)
        for (std::size_t i = 0; i < n.size(); ++i) {
          int v = 0;
          try {
            v = n[i].as<int>();
          } catch (const YAML::Exception&) {
            fail(path + "[" + std::to_string(i) + "]", "expected a whole number, got " + describe(n[i]));
          }
          if (v < 1 || v > 256) fail(path + "[" + std::to_string(i) + "]", "expected 1 to 256, got " + std::to_string(v));
          out.push_back(v);
        }
      else
        fail(path, "expected a number or a non-empty list of numbers, got " + describe(n));
      return out;
    };
    gen.sub_goals = counts("sub_goals");
    if (g.has("objects")) gen.objects = counts("objects");
    if (g.has("multi_step")) {
      if (g.raw("multi_step").IsScalar() && g.raw("multi_step").Scalar() == "all")
        gen.all_multi_step = true;
      else
        gen.multi_step = static_cast<int>(g.integer("multi_step", 0, 256));
    }
    gen.per_point = g.has("per_point") ? static_cast<int>(g.integer("per_point", 1, 10000)) : 1;
    gen.seed = g.has("seed") ? g.integer("seed", 0, std::numeric_limits<std::int32_t>::max()) : 1;
    for (int k : gen.sub_goals) {
      for (int n : gen.objects)
        if (n < k)
          fail(g.keyPath("objects"), "every point needs at least as many objects as sub-goals: " + std::to_string(n) +
                                         " objects for " + std::to_string(k) + " sub-goals");
      if (!gen.all_multi_step && gen.multi_step > k)
        fail(g.keyPath("multi_step"), std::to_string(gen.multi_step) + " two-action sub-goals is more than the " +
                                          std::to_string(k) + " sub-goals of a point (say 'all' for m = k)");
    }
    g.finish();
    d.generate = gen;
  }
  if (r.has("scenarios") || !d.generate) {
    const YAML::Node sc = r.has("scenarios") ? r.raw("scenarios") : YAML::Node();
    if (!sc.IsSequence() || sc.size() == 0)
      fail("extrinsic.scenarios", "expected a non-empty list of scenario names (or extrinsic.generate)");
    for (const auto& n : sc) d.scenarios.push_back(n.Scalar());
  }
  d.tests = r.has("tests") ? static_cast<int>(r.integer("tests", 1, 100000)) : 0;  // 0: only with --extrinsic-reps
  d.after_actions = r.has("after_actions") ? r.integer("after_actions", 1, 100'000'000) : 0;
  if (r.has("vary")) {
    const YAML::Node v = r.raw("vary");
    if (!v.IsMap()) fail("extrinsic.vary", "expected a map of config keys to lists of values");
    for (const auto& kv : v) {
      const std::string key = kv.first.Scalar();
      if (!kv.second.IsSequence() || kv.second.size() == 0)
        fail("extrinsic.vary." + key, "expected a non-empty list of values");
      std::vector<std::string> values;
      for (const auto& x : kv.second) values.push_back(YAML::Dump(x));
      d.vary.emplace_back(key, values);
    }
  }
  d.analysis = r.has("analysis") ? r.text("analysis") : "";
  if (!d.analysis.empty() && d.analysis != "utility" && d.analysis != "forward-models" && d.analysis != "search-reduction")
    fail("extrinsic.analysis", "expected utility, forward-models or search-reduction, got \"" + d.analysis + "\" (" + file + ")");
  r.finish();
  return d;
}

}  // namespace

YAML::Node loadGivenYaml(const std::string& file, const std::string& what, std::uintmax_t max_bytes) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) throw ConfigError(what + " " + file + ": no such file");
  if (!std::filesystem::is_regular_file(file, ec)) throw ConfigError(what + " " + file + ": not a regular file");
  const std::uintmax_t size = std::filesystem::file_size(file, ec);
  if (ec || size > max_bytes)
    throw ConfigError(what + " " + file + ": " + (ec ? "cannot read its size" : std::to_string(size) + " bytes, more than " +
                                                                                 std::to_string(max_bytes)));
  try {
    return YAML::LoadFile(file);
  } catch (const YAML::Exception& e) {
    throw ConfigError(what + " " + file + ": " + e.what());
  }
}

namespace {

// `key: none` (or an empty value) in an experiment file: drop what the extended experiment had.
bool isNone(const YAML::Node& n) { return n.IsNull() || (n.IsScalar() && n.Scalar() == "none"); }

// Every key a node sets (maps to any depth; a list is one key), under `path`, as set by `where`.
void recordKeys(const YAML::Node& node, const std::string& path, const std::string& where,
                std::map<std::string, std::string>& out) {
  if (!path.empty()) out[path] = where;
  if (node.IsMap())
    for (const auto& kv : node) recordKeys(kv.second, join(path, kv.first.Scalar()), where, out);
}

ExperimentFile loadExperimentChain(const std::string& config_dir, const std::string& name, int depth,
                                   const std::filesystem::path& from = {}) {
  const bool path = isExperimentPath(name);
  std::filesystem::path file;
  if (path) {
    file = std::filesystem::path(name).is_relative() && !from.empty() ? from.parent_path() / name : std::filesystem::path(name);
    if (!std::filesystem::is_regular_file(file))
      throw ConfigError("experiment file " + file.string() + " does not exist" +
                        (from.empty() ? std::string() : " (named by 'extends' in " + from.string() + ")"));
  } else {
    file = namedFile(config_dir, "experiments", "experiment", name);
  }
  YAML::Node root = loadFile(file);
  if (!root.IsMap()) throw ConfigError("config file " + file.string() + ": expected a map");
  ExperimentFile e;
  if (root["extends"].IsDefined()) {  // start from the whole of another experiment; this file changes what it states
    if (depth > 8) throw ConfigError("config file " + file.string() + ": 'extends' chain too long (a cycle?)");
    e = loadExperimentChain(config_dir, root["extends"].Scalar(), depth + 1, file);
    e.overlay = YAML::Clone(e.overlay);
    e.systems = YAML::Clone(e.systems);
    e.extrinsic_node = YAML::Clone(e.extrinsic_node);
    e.tables_node = YAML::Clone(e.tables_node);
  } else {
    e.overlay = YAML::Node(YAML::NodeType::Map);
  }
  e.name = path ? file.stem().string() : name;
  e.file = path ? std::filesystem::absolute(file).lexically_normal().string() : std::string();
  for (const auto& kv : root) {
    const std::string key = kv.first.Scalar();
    if (key == "extends") continue;
    if (key == "description") {
      e.description = kv.second.Scalar();
    } else if (key == "repetitions") {
      Reader r(root, "");
      e.repetitions = static_cast<int>(r.integer("repetitions", 1, 100000));
    } else if (key == "default_systems") {
      if (!kv.second.IsSequence()) fail("default_systems", "expected a list of systems (FIX, IGN, IMP)");
      for (const auto& s : kv.second) e.default_systems.push_back(toString(parseSystem(s.Scalar())));
    } else if (key == "extrinsic") {
      if (isNone(kv.second)) {  // `extrinsic: none`: no design, whatever the extended experiment had
        e.extrinsic.reset();
        e.extrinsic_node = YAML::Node();
        continue;
      }
      if (!kv.second.IsMap()) fail("extrinsic", "expected a map (or none), got " + describe(kv.second) + " (" + file.string() + ")");
      YAML::Node merged = e.extrinsic_node.IsMap() ? e.extrinsic_node : YAML::Node(YAML::NodeType::Map);
      // The tests' source: a file stating one (scenarios, or generate) does not keep the extended design's other.
      if (kv.second["scenarios"] && !kv.second["generate"]) merged.remove("generate");
      if (kv.second["generate"] && !kv.second["scenarios"]) merged.remove("scenarios");
      mergeInto(merged, kv.second);
      e.extrinsic_node = merged;
      e.extrinsic = parseDesign(merged, file.string());
    } else if (key == "tables") {
      if (isNone(kv.second)) {
        e.tables.reset();
        e.tables_node = YAML::Node();
        continue;
      }
      if (!kv.second.IsMap()) fail("tables", "expected a map (or none), got " + describe(kv.second) + " (" + file.string() + ")");
      YAML::Node merged = e.tables_node.IsMap() ? e.tables_node : YAML::Node(YAML::NodeType::Map);
      mergeInto(merged, kv.second);
      e.tables_node = merged;
      Reader t(merged, "tables");
      e.tables = TablesDesign{static_cast<int>(t.integer("count", 1, 100'000)), t.integer("seed", 0, INT64_MAX)};
      t.finish();
    } else if (key == "conditions") {
      if (!kv.second.IsMap() || kv.second.size() == 0)
        fail("conditions", "expected a map of condition names to lists of settings (key.path=value), got " +
                               describe(kv.second) + " (" + file.string() + ")");
      e.conditions.clear();
      for (const auto& c : kv.second) {
        const std::string cname = c.first.Scalar();
        if (cname.empty() || cname.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_") !=
                                 std::string::npos)
          fail("conditions." + cname, "a condition's name is part of run ids: letters, digits and _ only");
        if (!c.second.IsSequence()) fail("conditions." + cname, "expected a list of settings (key.path=value)");
        std::vector<std::string> settings;
        for (const auto& v : c.second) {
          if (!v.IsScalar() || v.Scalar().find('=') == std::string::npos)
            fail("conditions." + cname, "expected settings of the form key.path=value, got " + describe(v));
          settings.push_back(v.Scalar());
        }
        e.conditions.emplace_back(cname, settings);
      }
    } else if (key == "systems") {
      if (!e.systems.IsMap()) e.systems = YAML::Node(YAML::NodeType::Map);
      mergeInto(e.systems, kv.second);
      if (kv.second.IsMap())
        for (const auto& s : kv.second)
          recordKeys(s.second, "", "experiment file " + file.string() + ", block systems." + s.first.Scalar(),
                     e.system_sources[s.first.Scalar()]);
    } else {
      YAML::Node over(YAML::NodeType::Map);
      over[key] = kv.second;
      mergeInto(e.overlay, over);
      recordKeys(kv.second, key, "experiment file " + file.string() + ", block " + key, e.sources);
    }
  }
  if (!e.conditions.empty() && !e.tables)
    fail("conditions", "compares conditions on random tables: it needs a 'tables:' section (" + file.string() + ")");
  return e;
}
}  // namespace

ExperimentFile loadExperiment(const std::string& config_dir, const std::string& name) {
  return loadExperimentChain(config_dir, name, 0);
}

bool isExperimentPath(const std::string& name) {
  return name.find('/') != std::string::npos ||
         (name.size() > 5 && name.compare(name.size() - 5, 5, ".yaml") == 0);
}

YAML::Node effectiveConfig(const std::string& config_dir, const RunRequest& request) {
  YAML::Node root = loadFile(std::filesystem::path(config_dir) / "defaults.yaml");
  const ExperimentFile e = loadExperiment(config_dir, request.experiment);
  mergeInto(root, e.overlay);
  const std::string sys = toString(request.system);
  std::map<std::string, std::string> sources = e.sources;  // config key -> where it was given
  if (e.systems.IsMap() && e.systems[sys].IsDefined()) {
    if (!e.systems[sys].IsMap()) fail("systems." + sys, "expected a map of overrides");
    mergeInto(root, e.systems[sys]);
    if (const auto it = e.system_sources.find(sys); it != e.system_sources.end())
      for (const auto& [k, where] : it->second) sources[k] = where;
  }
  root["experiment"] = e.name;
  root["system"] = sys;
  root["seed"] = request.seed;
  if (request.steps) root["run"]["steps"] = *request.steps;
  for (const auto& setting : request.settings) {
    const auto eq = setting.find('=');
    if (eq == std::string::npos || eq == 0)
      throw ConfigError("setting \"" + setting + "\": expected key.path=value");
    const std::string path = setting.substr(0, eq);
    YAML::Node value;
    try {
      value = YAML::Load(setting.substr(eq + 1));
    } catch (const YAML::Exception& ex) {
      throw ConfigError("config key '" + path + "': value is not valid YAML: " + ex.what());
    }
    std::vector<std::string> parts;
    std::stringstream ss(path);
    for (std::string part; std::getline(ss, part, '.');) parts.push_back(part);
    std::vector<YAML::Node> chain{root};
    const auto keysOf = [](const YAML::Node& map) {
      std::vector<std::string> keys;
      for (const auto& kv : map) keys.push_back(kv.first.Scalar());
      return keys;
    };
    for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
      YAML::Node next = chain.back()[parts[i]];
      if (!next.IsDefined() || !next.IsMap()) {
        const std::string near = closestName(parts[i], keysOf(chain.back()));
        fail(path, "unknown key (no map '" + parts[i] + "'" + (near.empty() ? "" : "; did you mean '" + near + "'?") + ")");
      }
      chain.push_back(next);
    }
    if (!chain.back()[parts.back()].IsDefined())
      fail(path, unknownKey(path.substr(0, path.size() - parts.back().size() - (parts.size() > 1 ? 1 : 0)),
                            parts.back(), keysOf(chain.back())));
    chain.back()[parts.back()] = value;
    sources[path] = "--set " + setting;
  }
  try {
    parseRunConfig(root);  // validate now, before any process starts
  } catch (const ConfigError& e) {
    // Say where the key was given: the experiment file and its block, or --set.
    std::string where;
    for (std::string k = e.key(); !k.empty() && where.empty();) {
      if (auto it = sources.find(k); it != sources.end()) where = it->second;
      const auto dot = k.rfind('.');
      k = dot == std::string::npos ? std::string() : k.substr(0, dot);
    }
    if (where.empty()) throw;
    throw ConfigError(where + ": " + e.what(), e.key());
  }
  return root;
}

YAML::Node extrinsicConfig(const std::string& config_dir, const RunRequest& request, const std::string& checkpoint,
                           const std::string& scenario) {
  YAML::Node root = effectiveConfig(config_dir, request);
  const RunConfig base = parseRunConfig(root);
  loadScenario(config_dir, scenario, base.world);  // names the scenario's problem, if any
  root["phase"] = "extrinsic";
  root["run"]["steps"] = base.planner.budget;
  root["extrinsic"]["checkpoint"] = checkpoint;
  root["extrinsic"]["scenario"] = loadFile(std::filesystem::path(config_dir) / "scenarios" / (scenario + ".yaml"));
  parseRunConfig(root);
  return root;
}

YAML::Node scenarioNode(const Scenario& scenario) {
  YAML::Node root(YAML::NodeType::Map);
  root["name"] = scenario.name;
  if (!scenario.description.empty()) root["description"] = scenario.description;
  auto state = [](const ObjectState& s) {
    YAML::Node n(YAML::NodeType::Map);
    n["colour"] = toString(s.colour);
    YAML::Node pos(YAML::NodeType::Sequence);
    pos.push_back(s.x);
    pos.push_back(s.y);
    pos.SetStyle(YAML::EmitterStyle::Flow);
    n["position"] = pos;
    return n;
  };
  for (const ScenarioObject& o : scenario.objects) {
    YAML::Node n(YAML::NodeType::Map);
    n["shape"] = toString(o.shape);
    n["initial"] = state(o.initial);
    n["goal"] = state(o.goal);
    n["value"] = o.value;
    if (o.actions != 1) n["actions"] = o.actions;
    root["objects"].push_back(n);
  }
  return root;
}

YAML::Node extrinsicConfig(const std::string& config_dir, const RunRequest& request, const std::string& checkpoint,
                           const Scenario& scenario) {
  YAML::Node root = effectiveConfig(config_dir, request);
  const RunConfig base = parseRunConfig(root);
  root["phase"] = "extrinsic";
  root["run"]["steps"] = base.planner.budget;
  root["extrinsic"]["checkpoint"] = checkpoint;
  root["extrinsic"]["scenario"] = scenarioNode(scenario);
  parseRunConfig(root);  // validates the scenario in this world
  return root;
}

std::string emitYaml(const YAML::Node& node) {
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  out << node;
  return std::string(out.c_str()) + "\n";
}

}  // namespace afford
