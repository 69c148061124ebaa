#include "afford/config.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <filesystem>
#include <map>
#include <mutex>
#include <set>
#include <sstream>

#include "afford/image.hpp"

namespace afford {
namespace {

std::string join(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

[[noreturn]] void fail(const std::string& key, const std::string& what) {
  throw ConfigError("config key '" + key + "': " + what);
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
  template <typename E>
  E choice(const std::string& key, std::initializer_list<std::pair<const char*, E>> options) {
    const std::string s = text(key);
    std::string names;
    for (const auto& [name, value] : options) {
      if (s == name) return value;
      names += names.empty() ? name : std::string(", ") + name;
    }
    fail(join(path_, key), "unknown value \"" + s + "\" (expected one of: " + names + ")");
  }
  Reader map(const std::string& key) { return Reader(raw(key), join(path_, key)); }
  std::string keyPath(const std::string& key) const { return join(path_, key); }

  void finish() const {
    for (const auto& kv : node_) {
      const std::string k = kv.first.Scalar();
      if (!used_.count(k)) fail(join(path_, k), "unknown key");
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
std::string componentKind(Reader& r) {
  const std::string kind = r.text("kind");
  if (kind.empty()) fail(r.keyPath("kind"), "is empty");
  for (char ch : kind)
    if (!((ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9') || ch == '_' || ch == '-') || kind.size() > 64)
      fail(r.keyPath("kind"), "'" + kind + "' is not a name (lower-case letters, digits, '_', '-')");
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
  o.shape = r.choice<Shape>("shape", {{"square", Shape::Square}, {"circle", Shape::Circle},
                                       {"rectangle", Shape::Rectangle}});
  o.colour = r.choice<Colour>("colour", {{"red", Colour::Red}, {"green", Colour::Green},
                                          {"blue", Colour::Blue}});
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
  s.colour = r.choice<Colour>("colour", {{"red", Colour::Red}, {"green", Colour::Green}, {"blue", Colour::Blue}});
  const auto pos = numberList(r, "position", 2, w.table_min, w.table_max);
  s.x = pos[0];
  s.y = pos[1];
  r.finish();
  return s;
}

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
    so.shape = o.choice<Shape>("shape", {{"square", Shape::Square}, {"circle", Shape::Circle},
                                          {"rectangle", Shape::Rectangle}});
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

const char* toString(Shape s) {
  switch (s) {
    case Shape::Square: return "square";
    case Shape::Circle: return "circle";
    case Shape::Rectangle: return "rectangle";
  }
  return "?";
}
const char* toString(Colour c) {
  switch (c) {
    case Colour::Red: return "red";
    case Colour::Green: return "green";
    case Colour::Blue: return "blue";
  }
  return "?";
}
const char* toString(System s) {
  switch (s) {
    case System::FIX: return "FIX";
    case System::IGN: return "IGN";
    case System::IMP: return "IMP";
  }
  return "?";
}
System parseSystem(const std::string& s) {
  if (s == "FIX") return System::FIX;
  if (s == "IGN") return System::IGN;
  if (s == "IMP") return System::IMP;
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
        throw ConfigError(option + ": unknown system \"" + item + "\" in \"" + g + "\" (FIX, IGN, IMP, all, or a list: FIX,IMP)");
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
  c.heartbeat_ms = static_cast<int>(p.integer("heartbeat_ms", 10, 60'000));
  c.idle_announce_ms = static_cast<int>(p.integer("idle_announce_ms", 1, 60'000));
  c.retry_ms = static_cast<int>(p.integer("retry_ms", 1, 60'000));
  c.resend_batch = static_cast<int>(p.integer("resend_batch", 1, 100'000));
  c.resend_cap = static_cast<int>(p.integer("resend_cap", 1, 100'000));
  c.resend_budget = static_cast<int>(p.integer("resend_budget", 1, 1'000'000));
  c.stop_grace_ms = static_cast<int>(p.integer("stop_grace_ms", 0, 600'000));
  c.ready_timeout_ms = static_cast<int>(p.integer("ready_timeout_ms", 100, 600'000));
  c.close_timeout_ms = static_cast<int>(p.integer("close_timeout_ms", 100, 600'000));
  c.max_deferred = static_cast<int>(p.integer("max_deferred", 1, 1'000'000));
  c.queue_capacity = static_cast<int>(p.integer("queue_capacity", 30, 1'000'000));
  if (c.max_deferred < c.resend_batch)
    fail(p.keyPath("max_deferred"), "must be at least resend_batch (" + std::to_string(c.resend_batch) +
                                        "): a channel catching up defers up to a batch");
  if (c.close_timeout_ms <= c.stop_grace_ms)
    fail(p.keyPath("close_timeout_ms"), "must be longer than stop_grace_ms (the logger waits that long first)");
  Reader l = p.map("limits");
  c.limits.name_bytes = static_cast<int>(l.integer("name_bytes", 16, 65'536));
  c.limits.text_bytes = static_cast<int>(l.integer("text_bytes", 16, 1'048'576));
  c.limits.config_bytes = static_cast<int>(l.integer("config_bytes", 1024, 64 * 1'048'576));
  c.limits.objects = static_cast<int>(l.integer("objects", 1, 100'000));
  c.limits.focus_side = static_cast<int>(l.integer("focus_side", 3, 4096));
  c.limits.scene_side = static_cast<int>(l.integer("scene_side", 32, 8192));
  c.limits.sub_goals = static_cast<int>(l.integer("sub_goals", 1, 1'000'000));
  c.limits.run_id_bytes = static_cast<int>(l.integer("run_id_bytes", 16, 240));
  c.limits.peers = static_cast<int>(l.integer("peers", 8, 100'000));
  c.limits.control_messages = static_cast<int>(l.integer("control_messages", 4, 100'000));
  if (c.limits.run_id_bytes > c.limits.name_bytes)
    fail(l.keyPath("run_id_bytes"), "must be at most name_bytes (" + std::to_string(c.limits.name_bytes) + ")");
  l.finish();
  Reader b = p.map("bus");
  c.bus.max_message_bytes = static_cast<int>(b.integer("max_message_bytes", 65'536, 1 << 30));
  c.bus.fragment_bytes = static_cast<int>(b.integer("fragment_bytes", 65'536, 1 << 30));
  c.bus.fragment_timeout_ms = static_cast<int>(b.integer("fragment_timeout_ms", 10, 600'000));
  c.bus.queue_bytes = static_cast<int>(b.integer("queue_bytes", 65'536, 1 << 30));
  if (c.bus.queue_bytes < c.bus.max_message_bytes)
    fail(b.keyPath("queue_bytes"), "must be at least max_message_bytes (" + std::to_string(c.bus.max_message_bytes) +
                                       "): a whole message must fit in it");
  if (c.bus.fragment_bytes < c.bus.max_message_bytes)
    fail(b.keyPath("fragment_bytes"), "must be at least max_message_bytes (" + std::to_string(c.bus.max_message_bytes) +
                                          "): one whole message is reassembled in it");
  // The largest message a limit allows must fit on the bus (its other fields take a few KB at most).
  const long largest_text = std::max<long>(c.limits.config_bytes, c.limits.text_bytes);
  if (largest_text + 64 * 1024 > c.bus.max_message_bytes)
    fail(b.keyPath("max_message_bytes"), "must exceed limits.config_bytes and limits.text_bytes by 64 KiB (" +
                                             std::to_string(largest_text + 64 * 1024) +
                                             "): a RUN_CONFIG or STATUS at its limit must fit on the bus");
  b.finish();
  p.finish();
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
  std::string memory_keep_path;
  c.experiment = r.text("experiment");
  c.system = r.choice<System>("system", {{"FIX", System::FIX}, {"IGN", System::IGN}, {"IMP", System::IMP}});
  c.seed = r.integer("seed", 0, INT64_MAX);
  c.phase = r.choice<Phase>("phase", {{"intrinsic", Phase::Intrinsic}, {"extrinsic", Phase::Extrinsic}});
  {
    Reader run = r.map("run");
    c.steps = run.integer("steps", 1, 100'000'000);
    c.curve_interval = run.integer("curve_interval", 1, 100'000'000);
    c.checkpoint = run.has("checkpoint") ? run.text("checkpoint") : "";
    c.checkpoint_after_actions = run.integer("checkpoint_after_actions", 0, 100'000'000);
    c.record = run.choice<bool>("record", {{"true", true}, {"false", false}});
    run.finish();
  }
  {
    Reader w = r.map("world");
    c.world.size_px = static_cast<int>(w.integer("size_px", 32, 2048));
    c.world.object_size = w.number("object_size", 0.01, 0.3);
    const auto table = numberList(w, "table", 2, 0.0, 1.0);
    if (!(table[0] < table[1])) fail("world.table", "expected [min, max] with min < max");
    c.world.table_min = table[0];
    c.world.table_max = table[1];
    c.world.max_target_draws = static_cast<int>(w.integer("max_target_draws", 1, 1'000'000));
    c.world.positions =
        w.choice<Positions>("positions", {{"continuous", Positions::Continuous}, {"pixel", Positions::Pixel}});
    c.world.late_overlap = w.choice<bool>("late_overlap", {{"true", true}, {"false", false}});
    YAML::Node objs = w.raw("objects");
    if (!objs.IsSequence() || objs.size() == 0)
      fail("world.objects", "expected a non-empty list of objects, got " + describe(objs));
    for (std::size_t i = 0; i < objs.size(); ++i)
      c.world.objects.push_back(parseObject(objs[i], "world.objects[" + std::to_string(i) + "]", c.world));
    w.finish();
    checkWorldLayout(c.world);
  }
  {
    Reader e = r.map("eye");
    c.eye.focus_side = static_cast<int>(e.integer("focus_side", 3, 101));
    if (c.eye.focus_side % 2 == 0) fail("eye.focus_side", "must be odd (the gaze is the centre pixel)");
    c.eye.saliency_noise = e.number("saliency_noise", 0.0, 1.0);
    c.eye.saliency_sigma_px = e.number("saliency_sigma_px", 0.0, 20.0);
    c.eye.saliency_order = e.choice<SaliencyOrder>(
        "saliency_order",
        {{"smooth_then_noise", SaliencyOrder::SmoothThenNoise}, {"noise_then_smooth", SaliencyOrder::NoiseThenSmooth}});
    c.eye.change_sigma_px = e.number("change_sigma_px", 0.0, 20.0);
    const auto gaze = numberList(e, "initial_gaze", 2, 0.0, 1.0);
    c.eye.initial_gaze_x = gaze[0];
    c.eye.initial_gaze_y = gaze[1];
    c.eye.image_change_threshold = e.number("image_change_threshold", 0.0, 1.0);
    c.eye.position_change_threshold = e.number("position_change_threshold", 0.0, 1.0);
    c.eye.max_scan_draws = static_cast<int>(e.integer("max_scan_draws", 1, 100000));
    c.eye.attention =
        e.choice<Attention>("attention", {{"bottom_up", Attention::BottomUp}, {"top_down", Attention::TopDown}});
    e.finish();
  }
  {
    Reader p = r.map("predictors");
    Reader a = p.map("affordance");
    if (a.has("kind")) c.predictors.affordance_kind = componentKind(a);  // logs recorded before it have none: paper
    c.predictors.affordance_learning_rate = a.number("learning_rate", 0.0, 10.0);
    a.finish();
    Reader lp = p.map("learning_progress");
    c.predictors.learning_progress_learning_rate = lp.number("learning_rate", 0.0, 10.0);
    c.predictors.learning_progress_init = lp.number("init_magnitude", 0.0, 1.0);
    lp.finish();
    Reader what = p.map("what_effect");
    c.predictors.what_effect_learning_rate = what.number("learning_rate", 0.0, 10.0);
    what.finish();
    Reader where = p.map("where_effect");
    c.predictors.where_effect_learning_rate = where.number("learning_rate", 0.0, 10.0);
    where.finish();
    Reader mem = p.map("memory");
    c.predictors.memory.look_threshold = mem.number("look_threshold", 0.0, 1.0);
    c.predictors.memory.look_shift_px = static_cast<int>(mem.integer("look_shift_px", 0, 10));
    c.predictors.memory.max_looks = static_cast<int>(mem.integer("max_looks", 1, 100'000));
    c.predictors.memory.per_look_action = static_cast<int>(mem.integer("per_look_action", 1, 100'000));
    if (mem.has("keep"))  // logs recorded before it have none: auto
      c.predictors.memory.keep = mem.choice<MemoryKeep>(
          "keep", {{"auto", MemoryKeep::Auto}, {"always", MemoryKeep::Always}, {"never", MemoryKeep::Never}});
    memory_keep_path = mem.keyPath("keep");
    mem.finish();
    Reader rep = p.map("replay");
    c.predictors.replay.enabled = rep.choice<bool>("enabled", {{"true", true}, {"false", false}});
    c.predictors.replay.ratio = static_cast<int>(rep.integer("ratio", 0, 10'000));
    c.predictors.replay.effects_ratio = rep.number("effects_ratio", 0.0, 10'000.0);
    c.predictors.replay.sampling = rep.choice<ReplaySampling>(
        "sampling", {{"balanced", ReplaySampling::Balanced}, {"uniform", ReplaySampling::Uniform}});
    rep.finish();
    p.finish();
  }
  {
    Reader m = r.map("motivation");
    c.motivation.kind = componentKind(m);
    Reader nov = m.map("novelty");
    c.motivation.novelty_threshold = nov.number("threshold", 0.0, 1.0);
    nov.finish();
    c.motivation.fixed_threshold = m.number("fixed_threshold", 0.0, 1.0);
    c.motivation.leak = m.number("leak", 0.0, 1.0);
    c.motivation.initial_threshold = m.number("initial_threshold", 0.0, 1.0);
    c.motivation.act_margin = m.number("act_margin", 0.0, 1.0);
    c.motivation.imp_threshold_input = m.choice<ImpThresholdInput>(
        "imp_threshold_input",
        {{"signal", ImpThresholdInput::Signal}, {"observed_change", ImpThresholdInput::ObservedChange}});
    Reader rv = m.map("revisit");
    c.motivation.revisit.enabled = rv.choice<bool>("enabled", {{"true", true}, {"false", false}});
    c.motivation.revisit.after_steps = rv.integer("after_steps", 0, 100'000'000);
    c.motivation.revisit.order =
        rv.choice<RevisitOrder>("order", {{"actions", RevisitOrder::Actions}, {"random", RevisitOrder::Random}});
    if (c.motivation.revisit.enabled && c.motivation.kind != "paper")  // revisits are the paper motivation's
      fail(rv.keyPath("enabled"), "true needs motivation.kind paper (it is '" + c.motivation.kind + "')");
    rv.finish();
    m.finish();
  }
  if (c.predictors.memory.keep == MemoryKeep::Never && (c.predictors.replay.enabled || c.motivation.revisit.enabled))
    fail(memory_keep_path, "never, but " +
                               std::string(c.predictors.replay.enabled ? "predictors.replay.enabled" : "motivation.revisit.enabled") +
                               " is true, which needs the memory");
  if (r.has("extrinsic")) {
    Reader e = r.map("extrinsic");
    c.extrinsic_checkpoint = e.text("checkpoint");
    c.scenario = parseScenario(e.raw("scenario"), "extrinsic.scenario", c.world);
    validateScenario(*c.scenario, c.world);
    e.finish();
  }
  if (c.phase == Phase::Extrinsic && !c.scenario)
    fail("extrinsic", "missing (an extrinsic run needs a checkpoint and a scenario)");
  {
    Reader p = r.map("planner");
    c.planner.subgoal_match = p.number("subgoal_match", 0.0, 1.0);
    c.planner.image_match = p.number("image_match", 0.0, 1.0);
    c.planner.position_match = p.number("position_match", 0.0, 1.0);
    c.planner.position_metric = p.choice<PositionMetric>(
        "position_metric", {{"euclidean", PositionMetric::Euclidean}, {"half_euclidean", PositionMetric::HalfEuclidean}});
    c.planner.subgoal_timeout = static_cast<int>(p.integer("subgoal_timeout", 1, 1000));
    c.planner.budget = static_cast<int>(p.integer("budget", 1, 1'000'000));
    c.planner.max_attempts = static_cast<int>(p.integer("max_attempts", 1, 1'000'000));
    c.planner.restrict_by_affordance = p.choice<bool>("restrict_by_affordance", {{"true", true}, {"false", false}});
    c.planner.affordance_threshold = p.number("affordance_threshold", 0.0, 1.0);
    c.planner.success_distance = p.number("success_distance", 0.0, 1.0);
    c.planner.kind = p.choice<PlannerKind>("kind", {{"goal", PlannerKind::Goal}, {"utility", PlannerKind::Utility}});
    c.planner.attention = c.eye.attention;
    Reader search = p.map("search");
    c.planner.max_depth = static_cast<int>(search.integer("max_depth", 1, 4));
    c.planner.max_queries = static_cast<int>(search.integer("max_queries", 1, 10000));
    search.finish();
    Reader u = p.map("utility");
    c.planner.evaluation_iterations = static_cast<int>(u.integer("evaluation_iterations", 0, 1'000'000));
    c.planner.raise_leak = u.number("raise_leak", 0.0, 1.0);
    c.planner.lower_leak = u.number("lower_leak", 0.0, 1.0);
    u.finish();
    p.finish();
  }
  c.protocol = parseProtocol(r.raw("protocol"));
  r.finish();
  return c;
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
    throw ConfigError(std::string("unknown ") + kind + " \"" + name + "\" (known in " + config_dir + "/" + folder +
                      ": " + list + ")");
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

// `key: none` (or an empty value) in an experiment file: drop what the extended experiment had.
bool isNone(const YAML::Node& n) { return n.IsNull() || (n.IsScalar() && n.Scalar() == "none"); }

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
    } else {
      YAML::Node over(YAML::NodeType::Map);
      over[key] = kv.second;
      mergeInto(e.overlay, over);
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
  if (e.systems.IsMap() && e.systems[sys].IsDefined()) {
    if (!e.systems[sys].IsMap()) fail("systems." + sys, "expected a map of overrides");
    mergeInto(root, e.systems[sys]);
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
    for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
      YAML::Node next = chain.back()[parts[i]];
      if (!next.IsDefined() || !next.IsMap()) fail(path, "unknown key (no map '" + parts[i] + "')");
      chain.push_back(next);
    }
    if (!chain.back()[parts.back()].IsDefined()) fail(path, "unknown key");
    chain.back()[parts.back()] = value;
  }
  parseRunConfig(root);  // validate now, before any process starts
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
