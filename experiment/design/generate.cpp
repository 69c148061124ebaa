#include "experiment/design/generate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <stdexcept>

#include "afford/actions.hpp"
#include "afford/image.hpp"
#include "afford/rng.hpp"
#include "environment/environment.hpp"
#include "experiment/design/experiment_file.hpp"

namespace afford {
namespace {

struct Look {
  Shape shape;
  Colour colour;
  std::array<double, kNumActions> affordance;
};

// The distinct looks of the world, with the row the environment uses for each (its first).
std::vector<Look> looksOf(const WorldConfig& w) {
  std::vector<Look> looks;
  for (const ObjectSpec& o : w.objects) {
    const bool seen = std::any_of(looks.begin(), looks.end(),
                                  [&](const Look& l) { return l.shape == o.shape && l.colour == o.colour; });
    if (!seen) looks.push_back({o.shape, o.colour, o.affordance});
  }
  return looks;
}

const Look* findLook(const std::vector<Look>& looks, Shape s, Colour c) {
  for (const Look& l : looks)
    if (l.shape == s && l.colour == c) return &l;
  return nullptr;
}

bool afforded(const Look* l, int action) { return l && l->affordance[action] >= 1.0; }
int colourAction(Colour c) { return c == Colour::Green ? kTurnGreen : c == Colour::Red ? kTurnRed : kTurnBlue; }

// Centres closer than this (pixels, on both axes) may break validateScenario's free-window rule or, in the
// continuous world, where shapes drawn from real centres reach a pixel further, the environment's rule that a
// moved shape touches no other.
int separation(const WorldConfig& w, int focus_side) {
  int half = focus_side / 2;
  for (Shape s : {Shape::Square, Shape::Circle, Shape::Rectangle})
    for (const Pixel& p : shapeFootprint(s, w)) half = std::max({half, std::abs(p.col), std::abs(p.row)});
  return 2 * (half + 1) + 2;
}

// A sub-goal for an object of look `l`: its goal colour, whether it moves, and the order of its actions.
struct Change {
  Colour colour;
  bool moves = false;
  bool move_first = false;
};

std::vector<Change> changesOf(const Look& l, const std::vector<Look>& looks, bool two_actions) {
  std::vector<Change> out;
  for (Colour c : {Colour::Red, Colour::Green, Colour::Blue}) {
    if (c == l.colour || !afforded(&l, colourAction(c))) continue;
    if (!two_actions) {
      out.push_back({c, false, false});
    } else if (afforded(&l, kMove)) {
      out.push_back({c, true, true});  // move, then turn
    } else if (afforded(findLook(looks, l.shape, c), kMove)) {
      out.push_back({c, true, false});  // turn, then move as the new look
    }
  }
  if (!two_actions && afforded(&l, kMove)) out.push_back({l.colour, true, false});
  return out;
}

// One draw of a scenario (attempt `attempt` of its key): the draws come in a
// fixed order, so that the same key gives the same scenario.
class Draw {
 public:
  Draw(const WorldConfig& w, int apart, std::int64_t seed, std::int64_t index, int attempt)
      : w_(w), apart_(apart), rng_(seed, index, Purpose::ScenarioGeneration, static_cast<std::uint64_t>(attempt)) {}
  std::size_t pick(std::size_t n) { return static_cast<std::size_t>(rng_.uniform(draw_++) * static_cast<double>(n)); }
  // A place apart from every initial and goal place drawn so far, if one comes within the draws allowed.
  std::optional<std::pair<double, double>> freePlace() {
    constexpr int kPlaceDraws = 500;
    for (int d = 0; d < kPlaceDraws; ++d) {
      const double x = rng_.uniform(draw_++, w_.table_min, w_.table_max);
      const double y = rng_.uniform(draw_++, w_.table_min, w_.table_max);
      const Pixel p = toPixel(x, y, w_.size_px);
      const bool clear = std::all_of(taken_.begin(), taken_.end(), [&](const Pixel& q) {
        return std::abs(p.col - q.col) >= apart_ || std::abs(p.row - q.row) >= apart_;
      });
      if (clear) {
        taken_.push_back(p);
        return std::make_pair(x, y);
      }
    }
    return std::nullopt;
  }

 private:
  const WorldConfig& w_;
  const int apart_;
  const KeyedRng rng_;
  std::uint64_t draw_ = 0;
  std::vector<Pixel> taken_;  // every initial and goal place so far
};

// The looks that can take each kind of sub-goal: one action, two actions.
struct SubGoalLooks {
  std::vector<const Look*> one, two;
};

// The objects of one draw, sub-goals first, and each one's change; nullopt if the table has no room.
std::optional<std::pair<Scenario, std::vector<Change>>> drawObjects(Draw& d, const ScenarioSpec& spec,
                                                                     const std::vector<Look>& looks,
                                                                     const SubGoalLooks& can) {
  Scenario scenario;
  std::vector<Change> changes;
  std::vector<std::pair<Shape, Colour>> asked;  // the looks two-action sub-goals ask for: no other object starts so
  for (int i = 0; i < spec.objects; ++i) {
    const bool has_goal = i < spec.sub_goals, two_actions = i < spec.multi_step;
    std::vector<const Look*> choices;
    for (const Look* l : has_goal ? (two_actions ? can.two : can.one) : std::vector<const Look*>{}) choices.push_back(l);
    if (!has_goal)
      for (const Look& l : looks) choices.push_back(&l);
    std::vector<const Look*> allowed;
    for (const Look* l : choices)
      if (std::find(asked.begin(), asked.end(), std::make_pair(l->shape, l->colour)) == asked.end()) allowed.push_back(l);
    if (allowed.empty()) allowed = choices;  // the checks after draw the scenario again
    const Look& l = *allowed[d.pick(allowed.size())];
    ScenarioObject o;
    o.shape = l.shape;
    o.value = 1.0;
    o.actions = two_actions ? 2 : 1;
    const auto at = d.freePlace();
    if (!at) return std::nullopt;
    o.initial = {l.colour, at->first, at->second};
    o.goal = o.initial;
    Change ch{l.colour, false, false};
    if (has_goal) {
      const std::vector<Change> options = changesOf(l, looks, two_actions);
      ch = options[d.pick(options.size())];
      o.goal.colour = ch.colour;
      if (two_actions) asked.emplace_back(l.shape, ch.colour);
    }
    changes.push_back(ch);
    scenario.objects.push_back(o);
  }
  // Move targets after every start is placed, apart from all of them and from each other.
  for (std::size_t i = 0; i < changes.size(); ++i) {
    if (!changes[i].moves) continue;
    const auto to = d.freePlace();
    if (!to) return std::nullopt;
    scenario.objects[i].goal.x = to->first;
    scenario.objects[i].goal.y = to->second;
  }
  // The objects' order is the order of their draws: sub-goals first. Shuffle so that the scan order says nothing.
  std::vector<std::size_t> order(scenario.objects.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  for (std::size_t i = order.size(); i > 1; --i) std::swap(order[i - 1], order[d.pick(i)]);
  Scenario shuffled = scenario;
  std::vector<Change> shuffled_changes = changes;
  for (std::size_t i = 0; i < order.size(); ++i) {
    shuffled.objects[i] = scenario.objects[order[i]];
    shuffled_changes[i] = changes[order[i]];
  }
  return std::make_pair(std::move(shuffled), std::move(shuffled_changes));
}

// A two-action sub-goal must need its two actions: if another object starts
// with the look it asks for, one move of that object would reach it.
bool oneMoveReaches(const Scenario& s) {
  const auto& objs = s.objects;
  return std::any_of(objs.begin(), objs.end(), [&](const ScenarioObject& o) {
    return o.actions >= 2 && std::any_of(objs.begin(), objs.end(), [&](const ScenarioObject& other) {
             return &other != &o && other.shape == o.shape && other.initial.colour == o.goal.colour;
           });
  });
}

// The true plan of the changes: per object, its actions in their order.
std::vector<PlannedAction> truePlan(const Scenario& s, const std::vector<Change>& changes) {
  std::vector<PlannedAction> plan;
  for (std::size_t i = 0; i < s.objects.size(); ++i) {
    const ScenarioObject& o = s.objects[i];
    const Change& ch = changes[i];
    const int obj = static_cast<int>(i);
    // A move starts where the object starts (a colour change leaves it in place); a turn acts where it is then.
    const PlannedAction move{obj, kMove, o.initial.x, o.initial.y, o.goal.x, o.goal.y};
    const bool turns = ch.colour != o.initial.colour;
    const double cx = ch.moves && ch.move_first ? o.goal.x : o.initial.x;
    const double cy = ch.moves && ch.move_first ? o.goal.y : o.initial.y;
    const PlannedAction turn{obj, colourAction(ch.colour), cx, cy, -1, -1};
    if (ch.moves && ch.move_first) plan.push_back(move);
    if (turns) plan.push_back(turn);
    if (ch.moves && !ch.move_first) plan.push_back(move);
  }
  return plan;
}

// The plan, played in the environment, reaches the goal.
bool planSolves(const RunConfig& config, const GeneratedScenario& g) {
  Environment env(config, g.scenario);
  std::int64_t step = 0;
  for (const PlannedAction& a : g.plan) {
    std::optional<std::pair<double, double>> target;
    if (a.action == kMove) target = std::make_pair(a.target_x, a.target_y);
    if (!env.execute(step++, a.action, a.x, a.y, target).succeeded) return false;
  }
  return env.goalDistance() < config.planner.success_distance;
}

}  // namespace

std::vector<ScenarioSpec> designPoints(const GenerateDesign& design) {
  std::vector<ScenarioSpec> points;
  for (int k : design.sub_goals) {
    const std::vector<int> ns = design.objects.empty() ? std::vector<int>{k} : design.objects;
    for (int n : ns) points.push_back({n, k, design.all_multi_step ? k : design.multi_step});
  }
  return points;
}

std::string generatedName(const ScenarioSpec& spec, std::int64_t seed, std::int64_t index) {
  return "gen-k" + std::to_string(spec.sub_goals) + "-m" + std::to_string(spec.multi_step) + "-n" +
         std::to_string(spec.objects) + "-s" + std::to_string(seed) + "-i" + std::to_string(index);
}

GeneratedScenario generateScenario(const RunConfig& config, const ScenarioSpec& spec, std::int64_t seed,
                                   std::int64_t index) {
  if (spec.objects < 1) throw std::invalid_argument("objects = " + std::to_string(spec.objects) + ": at least 1");
  if (spec.sub_goals < 0 || spec.sub_goals > spec.objects)
    throw std::invalid_argument("sub_goals = " + std::to_string(spec.sub_goals) + ": from 0 to objects (" +
                                std::to_string(spec.objects) + ")");
  if (spec.multi_step < 0 || spec.multi_step > spec.sub_goals)
    throw std::invalid_argument("multi_step = " + std::to_string(spec.multi_step) + ": from 0 to sub_goals (" +
                                std::to_string(spec.sub_goals) + ")");
  const WorldConfig& w = config.world;
  if (w.kind != WorldKind::Grid)
    throw std::invalid_argument("scenarios are generated in the paper's world (shapes and colours) only; the table "
                                "world's scenarios are files of config/scenarios with `world: table`");
  const std::vector<Look> looks = looksOf(w);
  SubGoalLooks can;
  for (const Look& l : looks) {
    if (!changesOf(l, looks, false).empty()) can.one.push_back(&l);
    if (!changesOf(l, looks, true).empty()) can.two.push_back(&l);
  }
  if (spec.sub_goals > spec.multi_step && can.one.empty())
    throw std::runtime_error("no look of the world affords a colour change or a move (entries of 1)");
  if (spec.multi_step > 0 && can.two.empty())
    throw std::runtime_error("no look of the world affords a colour change and a move in some order (entries of 1)");
  const int apart = separation(w, config.eye.focus_side);
  constexpr int kAttempts = 200;
  for (int attempt = 0; attempt < kAttempts; ++attempt) {
    Draw d(w, apart, seed, index, attempt);
    auto drawn = drawObjects(d, spec, looks, can);
    if (!drawn) continue;
    GeneratedScenario g;
    g.scenario = std::move(drawn->first);
    g.scenario.name = generatedName(spec, seed, index);
    g.scenario.description = "generated: " + std::to_string(spec.sub_goals) + " sub-goal(s), " +
                             std::to_string(spec.multi_step) + " of two actions, " + std::to_string(spec.objects) +
                             " object(s)";
    try {
      validateScenario(g.scenario, w);
    } catch (const ConfigError&) {
      continue;  // a layout the validation refuses (shapes' reach): draw again
    }
    if (oneMoveReaches(g.scenario)) continue;
    g.plan = truePlan(g.scenario, drawn->second);
    if (planSolves(config, g)) return g;
  }
  throw std::runtime_error("no scenario of " + std::to_string(spec.objects) + " objects with " +
                           std::to_string(spec.sub_goals) + " sub-goal(s) fits the world's table (" +
                           std::to_string(kAttempts) + " draws): a larger table or fewer objects");
}

}  // namespace afford
