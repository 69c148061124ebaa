#include "experiment/present/explain_text.hpp"

#include <fmt/printf.h>

#include <algorithm>
#include <map>

#include "afford/actions.hpp"

namespace afford {

using fmt::sprintf;
using nlohmann::json;

namespace {

std::string nameOfAction(WorldKind world, int a) {
  return validAction(a) ? std::string(actionName(world, a)) : "action " + std::to_string(a);
}
// The world of a folder's tests (their actions' names): the first's.
WorldKind worldOf(const ExplainSummary& s) { return s.tests.empty() ? WorldKind::Grid : s.tests.front().world; }
const char* kindName(PlannerKind k) { return nameOf(kPlannerKindNames, k); }
const char* metricName(PositionMetric m) { return nameOf(kPositionMetricNames, m); }

}  // namespace

// ---- one test ---------------------------------------------------------------------------

namespace {

std::string endText(const Explanation& e) {
  const PlannerConfig& p = e.planner;
  if (e.end == "solved")
    return sprintf("solved at iteration %d (counted from 1): the goal distance %.3g fell below planner.success_distance %.3g",
                  e.completion, e.final_goal_distance, p.success_distance);
  if (e.end == "budget")
    return sprintf("not solved: the budget of %d iterations ran out (planner.budget)%s", p.budget,
                  e.also_out_of_attempts ? sprintf(", and the %d actions of planner.max_attempts with it", p.max_attempts).c_str()
                                         : "");
  if (e.end == "attempts")
    return sprintf("not solved: the %d executed actions of planner.max_attempts ran out, after %lld of %d iterations",
                  p.max_attempts, static_cast<long long>(e.iterations), p.budget);
  return "not solved, and neither the budget nor the action limit was reached (see the warnings)";
}

std::string subGoalText(const Explanation& e, std::size_t i) {
  const ExplainedSubGoal& g = e.sub_goals[i];
  std::string how;
  if (g.reached_when_picked)
    how = sprintf("reached already when picked, at iteration %lld", static_cast<long long>(g.first_step));
  else if (g.ended == "reached")
    how = sprintf("reached at iteration %lld", static_cast<long long>(g.last_step));
  else if (g.ended == "timeout")
    how = sprintf("not reached: abandoned after %d iterations (planner.subgoal_timeout %d)", g.iterations,
                 e.planner.subgoal_timeout);
  else if (g.ended == "left")
    how = "not reached: left after weighing an action (Algorithm 3)";
  else if (g.ended == "not_actionable")
    how = sprintf("not reached: no remembered object was left to try for it, after %d iterations (top-down attention)",
                 g.iterations);
  else
    how = "not reached: the test ended with it";
  return sprintf("  #%zu at (%.4f, %.4f), iterations %lld..%lld: %d spent, %d actions checked, %d taken; %s", i, g.x, g.y,
                static_cast<long long>(g.first_step), static_cast<long long>(g.last_step), g.iterations,
                g.actions_checked, g.actions_taken, how.c_str());
}

std::string closestText(const ExplainedSubGoal& g, const PlannerConfig& p, WorldKind world) {
  if (!g.closest) return "no action was checked";
  const ExplainedCheck& c = *g.closest;
  // An action that passed both thresholds is no miss: the sub-goal was lost
  // after it (the action failed, or the utility planner did not take it).
  return sprintf("%s: %s at iteration %lld, what %.5f (%s %.5f), where %.4f (%s %.4f)",
                c.passes() ? "passed" : "closest", nameOfAction(world, c.action).c_str(),
                static_cast<long long>(g.closest_step), c.what_distance, c.what_ok ? "<" : "not <", p.image_match,
                c.where_distance, c.where_ok ? "<=" : "not <=", p.position_match);
}

}  // namespace

std::string explanationText(const Explanation& e) {
  const PlannerConfig& p = e.planner;
  std::string out;
  out += sprintf("test %s: scenario %s, %s planner (Algorithm %d), %s agent of experiment %s, seed %lld\n", e.run_id.c_str(),
                e.scenario.c_str(), kindName(p.kind), p.kind == PlannerKind::Utility ? 3 : 2, e.system.c_str(),
                e.experiment.c_str(), static_cast<long long>(e.seed));
  out += "  " + endText(e) + "\n";
  out += sprintf("  %lld iterations, %d actions taken, utility %.3g; goal distance %.3g at the start, %.3g at the end\n",
                static_cast<long long>(e.iterations), e.attempts, e.utility, e.start_goal_distance, e.final_goal_distance);
  out += sprintf("  thresholds: what-distance < %.5g (planner.image_match), where-distance (%s) <= %.5g "
                "(planner.position_match), sub-goal reached < %.5g (planner.subgoal_match), sub-goal timeout %d "
                "iterations",
                p.image_match, metricName(p.position_metric), p.position_match, p.subgoal_match, p.subgoal_timeout);
  if (p.restrict_by_affordance) out += sprintf(", actions checked if afforded > %.3g", p.affordance_threshold);
  out += "\n";
  out += sprintf("sub-goals (%zu):\n", e.sub_goals.size());
  for (std::size_t i = 0; i < e.sub_goals.size(); ++i) {
    out += subGoalText(e, i) + "\n";
    if (!e.sub_goals[i].reached) out += "      " + closestText(e.sub_goals[i], p, e.world) + "\n";
    const ExplainedSubGoal& g = e.sub_goals[i];
    if (g.place_affordance && g.colour_action >= 0)
      out += sprintf("      the object at its place: %s afforded %.3f%s\n", nameOfAction(e.world, g.colour_action).c_str(),
                    (*g.place_affordance)[static_cast<std::size_t>(g.colour_action)],
                    g.colourActionBlocked(p) ? sprintf(" (not above %.3g: never asked about)", p.affordance_threshold).c_str()
                                              : "");
  }
  out += "iterations:\n";
  for (const ExplainedIteration& it : e.steps) {
    out += sprintf("  [%lld] ", static_cast<long long>(it.step));
    if (it.sub_goal < 0)
      out += "no sub-goal known\n";
    else if (it.picked)
      out += sprintf("sub-goal #%d picked at (%.4f, %.4f)\n", it.sub_goal, e.sub_goals[static_cast<std::size_t>(it.sub_goal)].x,
                    e.sub_goals[static_cast<std::size_t>(it.sub_goal)].y);
    else
      out += sprintf("sub-goal #%d\n", it.sub_goal);
    auto reach = [&](const ExplainedReachCheck& c) {
      out += sprintf("      scene at the sub-goal%s: distance %.5f, %s\n", c.after_action ? " after the action" : "",
                    c.distance, c.reached ? "reached" : "not reached");
    };
    for (const ExplainedReachCheck& c : it.reach_checks)
      if (!c.after_action) reach(c);
    if (it.scanned) {
      out += sprintf("      object at (%.4f, %.4f)", it.object_x, it.object_y);
      if (it.affordance) {
        out += ", affordances:";
        for (int a = 0; a < kNumActions; ++a)
          out += sprintf("%s %s %.3f", a ? "," : "", nameOfAction(e.world, a).c_str(), (*it.affordance)[static_cast<std::size_t>(a)]);
      }
      out += "\n";
      if (it.candidates.empty()) out += "      no action afforded: nothing checked\n";
    }
    for (const ExplainedCheck& c : it.checks)
      out += sprintf("      %-10s what %.5f %s %.5g %s, where %.4f %s %.5g %s%s\n", nameOfAction(e.world, c.action).c_str(),
                    c.what_distance, c.what_ok ? "<" : ">=", p.image_match, c.what_ok ? "ok" : "no", c.where_distance,
                    c.where_ok ? "<=" : ">", p.position_match, c.where_ok ? "ok" : "no",
                    !c.checked ? "  (not compared: an earlier action passed)" : c.passes() ? "  <- passes" : "");
    if (it.executed >= 0) {
      out += sprintf("      executed: %s", nameOfAction(e.world, it.executed).c_str());
      if (takesPlace(e.world, it.executed)) out += sprintf(" to (%.4f, %.4f)", it.target_x, it.target_y);
      out += sprintf("; goal distance after: %.3g\n", it.goal_distance_after);
    } else if (std::any_of(it.checks.begin(), it.checks.end(), [](const ExplainedCheck& c) { return c.passes(); })) {
      out += "      nothing executed (Algorithm 3 weighed the action's utility)\n";
    }
    for (const ExplainedReachCheck& c : it.reach_checks)
      if (c.after_action) reach(c);
  }
  for (const std::string& w : e.warnings) out += "warning: " + w + "\n";
  return out;
}

json explanationJson(const Explanation& e, bool with_steps) {
  const PlannerConfig& p = e.planner;
  auto check = [&e](const ExplainedCheck& c) {
    return json{{"action", c.action},         {"action_name", nameOfAction(e.world, c.action)}, {"what_distance", c.what_distance},
                {"what_ok", c.what_ok},       {"where_distance", c.where_distance},   {"where_ok", c.where_ok},
                {"checked", c.checked},       {"passes", c.passes()}};
  };
  json j = {{"log", e.log},
            {"run_id", e.run_id},
            {"experiment", e.experiment},
            {"system", e.system},
            {"seed", e.seed},
            {"agent", e.agent},
            {"scenario", e.scenario},
            {"planner",
             {{"kind", kindName(p.kind)},
              {"image_match", p.image_match},
              {"position_match", p.position_match},
              {"position_metric", metricName(p.position_metric)},
              {"subgoal_match", p.subgoal_match},
              {"subgoal_timeout", p.subgoal_timeout},
              {"budget", p.budget},
              {"max_attempts", p.max_attempts},
              {"success_distance", p.success_distance},
              {"restrict_by_affordance", p.restrict_by_affordance},
              {"affordance_threshold", p.affordance_threshold}}},
            {"success", e.success},
            {"end", e.end},
            {"also_out_of_attempts", e.also_out_of_attempts},
            {"completion", e.completion},
            {"iterations", e.iterations},
            {"attempts", e.attempts},
            {"utility", e.utility},
            {"start_goal_distance", e.start_goal_distance},
            {"final_goal_distance", e.final_goal_distance},
            {"sub_goals", json::array()},
            {"warnings", e.warnings}};
  for (const ExplainedSubGoal& g : e.sub_goals) {
    json s = {{"x", g.x},
              {"y", g.y},
              {"first_step", g.first_step},
              {"last_step", g.last_step},
              {"iterations", g.iterations},
              {"actions_checked", g.actions_checked},
              {"actions_taken", g.actions_taken},
              {"reached", g.reached},
              {"reached_when_picked", g.reached_when_picked},
              {"ended", g.ended},
              {"closest", nullptr}};
    if (g.closest) {
      s["closest"] = check(*g.closest);
      s["closest"]["step"] = g.closest_step;
    }
    s["place_affordance"] = g.place_affordance ? json(*g.place_affordance) : json(nullptr);
    s["colour_action"] = g.colour_action >= 0 ? json(nameOfAction(e.world, g.colour_action)) : json(nullptr);
    s["colour_action_blocked"] = g.colourActionBlocked(p);
    j["sub_goals"].push_back(s);
  }
  if (!with_steps) return j;
  j["steps"] = json::array();
  for (const ExplainedIteration& it : e.steps) {
    json s = {{"step", it.step},       {"sub_goal", it.sub_goal}, {"picked", it.picked},
              {"scanned", it.scanned}, {"reached", it.reached()}, {"reach_checks", json::array()},
              {"candidates", it.candidates}, {"checks", json::array()}};
    for (const ExplainedReachCheck& c : it.reach_checks)
      s["reach_checks"].push_back({{"after_action", c.after_action}, {"distance", c.distance}, {"reached", c.reached}});
    if (it.scanned) {
      s["object"] = {{"x", it.object_x}, {"y", it.object_y}};
      s["affordance"] = it.affordance ? json(*it.affordance) : json(nullptr);
    }
    for (const ExplainedCheck& c : it.checks) s["checks"].push_back(check(c));
    if (it.executed >= 0)
      s["executed"] = {{"action", it.executed},
                       {"action_name", nameOfAction(e.world, it.executed)},
                       {"target_x", it.target_x},
                       {"target_y", it.target_y},
                       {"goal_distance_after", it.goal_distance_after}};
    else
      s["executed"] = nullptr;
    j["steps"].push_back(s);
  }
  return j;
}

// ---- a folder of run logs -------------------------------------------------------------

namespace {

// End reasons in a fixed order, every one named even when none ended so.
const char* const kEnds[] = {"solved", "budget", "attempts", "unknown"};

std::map<std::string, std::map<std::string, int>> endsBySystem(const ExplainSummary& s) {
  std::map<std::string, std::map<std::string, int>> out;
  for (const Explanation& t : s.tests) {
    ++out[""][t.end];
    ++out[t.system][t.end];
  }
  return out;
}

std::string countsText(const std::map<std::string, int>& counts) {
  std::string out;
  int total = 0;
  for (const char* end : kEnds) {
    const auto it = counts.find(end);
    const int n = it == counts.end() ? 0 : it->second;
    total += n;
    if (n == 0 && std::string(end) == "unknown") continue;
    out += sprintf("%s%s %d", out.empty() ? "" : ", ", end, n);
  }
  return out + sprintf(" (%d tests)", total);
}

}  // namespace

std::string summaryText(const ExplainSummary& s) {
  std::string out = sprintf("%zu extrinsic test(s) under %s", s.tests.size(), s.root.c_str());
  if (!s.skipped.empty()) out += sprintf(" (%zu other run log(s) skipped)", s.skipped.size());
  out += "\n";
  out += sprintf("%-44s %-6s %-12s %-8s %-9s %10s %8s %7s %9s %8s\n", "test", "system", "scenario", "planner", "end",
                "completion", "actions", "utility", "sub-goals", "warnings");
  for (const Explanation& t : s.tests) {
    int reached = 0;
    for (const auto& g : t.sub_goals) reached += g.reached;
    out += sprintf("%-44s %-6s %-12s %-8s %-9s %10d %8d %7.3g %4d/%-4zu %8zu\n", t.run_id.c_str(), t.system.c_str(),
                  t.scenario.c_str(), kindName(t.planner.kind), t.end.c_str(), t.completion, t.attempts, t.utility,
                  reached, t.sub_goals.size(), t.warnings.size());
  }
  const auto ends = endsBySystem(s);
  out += "end reasons: " + countsText(ends.count("") ? ends.at("") : std::map<std::string, int>{}) + "\n";
  for (const auto& [system, counts] : ends)
    if (!system.empty()) out += "  " + system + ": " + countsText(counts) + "\n";
  bool header = false;
  for (const Explanation& t : s.tests) {
    if (t.success) continue;
    if (!header)
      out += "closest misses of the failed tests (each sub-goal not reached: of its checked actions, one whose "
             "predicted place matched if any, with the smallest what-distance):\n";
    header = true;
    int missed = 0;
    for (std::size_t i = 0; i < t.sub_goals.size(); ++i) {
      const ExplainedSubGoal& g = t.sub_goals[i];
      if (g.reached) continue;
      ++missed;
      out += sprintf("  %s #%zu at (%.4f, %.4f), %s: %s\n", t.run_id.c_str(), i, g.x, g.y, g.ended.c_str(),
                    closestText(g, t.planner, t.world).c_str());
    }
    if (missed == 0)
      out += sprintf("  %s: every sub-goal it picked was reached; it ended by %s before it picked another\n",
                    t.run_id.c_str(), t.end.c_str());
  }
  for (const Explanation& t : s.tests)
    for (const std::string& w : t.warnings) out += "warning: " + t.run_id + ": " + w + "\n";
  for (const auto& [dir, why] : s.errors) out += "error: " + why + "\n";
  return out;
}

json summaryJson(const ExplainSummary& s) {
  json j = {{"root", s.root}, {"tests", json::array()}, {"end_reasons", json::object()}, {"skipped", json::array()},
            {"errors", json::array()}};
  for (const Explanation& t : s.tests) j["tests"].push_back(explanationJson(t, /*steps=*/false));
  for (const auto& [system, counts] : endsBySystem(s)) {
    json c = json::object();
    for (const char* end : kEnds) c[end] = counts.count(end) ? counts.at(end) : 0;
    if (system.empty())
      j["end_reasons"]["all"] = c;
    else
      j["end_reasons"][system] = c;
  }
  for (const auto& [dir, why] : s.skipped) j["skipped"].push_back({{"log", dir}, {"why", why}});
  for (const auto& [dir, why] : s.errors) j["errors"].push_back({{"log", dir}, {"error", why}});
  return j;
}

// ---- per agent and sub-goal -----------------------------------------------------------

namespace {

std::string placeText(double x, double y) { return sprintf("(%.3f, %.3f)", x, y); }

double median(const std::vector<double>& sorted) {
  const std::size_t n = sorted.size();
  return n % 2 ? sorted[n / 2] : (sorted[n / 2 - 1] + sorted[n / 2]) / 2;
}

}  // namespace

std::string byAgentText(const ExplainSummary& s) {
  const std::vector<AgentSubGoal> agents = subGoalsByAgent(s);
  const std::vector<SystemSubGoal> systems = subGoalsBySystem(agents);
  std::string out = sprintf("%zu extrinsic test(s) under %s, by system, scenario and sub-goal\n", s.tests.size(), s.root.c_str());
  out += "closest: each agent's best check over its tests (one that passed; else, of those whose predicted place\n"
         "matched, the smallest what-distance; else the smallest what-distance); a miss is a closest check not below\n"
         "planner.image_match (what) or not within planner.position_match (where); blocked: the\n"
         "colour action the object at the sub-goal's place needs was not above planner.affordance_threshold\n\n";
  out += sprintf("%-16s %-6s %-12s %-16s %6s %6s %10s %10s %10s %5s %6s %8s\n", "experiment", "system", "scenario", "sub-goal",
                "agents", "always", "closest", "median", "max", "what", "where", "blocked");
  for (const SystemSubGoal& r : systems) {
    const bool any = !r.closest_what.empty();
    out += sprintf("%-16s %-6s %-12s %-16s %6d %6d %10s %10s %10s %5d %6d %8d\n", r.experiment.c_str(), r.system.c_str(),
                  r.scenario.c_str(), placeText(r.x, r.y).c_str(), r.agents, r.agents_always,
                  any ? sprintf("%.5f", r.closest_what.front()).c_str() : "-",
                  any ? sprintf("%.5f", median(r.closest_what)).c_str() : "-",
                  any ? sprintf("%.5f", r.closest_what.back()).c_str() : "-", r.agents_what_miss, r.agents_where_miss,
                  r.agents_colour_blocked);
  }
  out += "\nper agent (reached k/n; the causes in the tests that did not reach it: no check, what miss, where miss,\n"
         "passed both; the closest check over its tests; the place's colour action and its affordance):\n";
  out += sprintf("%-16s %-6s %-12s %-16s %-40s %7s %-15s %-11s %9s %8s %s\n", "experiment", "system", "scenario", "sub-goal",
                "agent", "reached", "causes n/w/p/b", "closest", "what", "where", "colour action");
  for (const AgentSubGoal& a : agents) {
    std::string colour = "-";
    if (a.place_affordance && a.colour_action >= 0)
      colour = sprintf("%s %.3f%s", nameOfAction(worldOf(s), a.colour_action).c_str(),
                      (*a.place_affordance)[static_cast<std::size_t>(a.colour_action)],
                      a.colour_blocked ? sprintf(" blocked in %d", a.colour_blocked).c_str() : "");
    out += sprintf("%-16s %-6s %-12s %-16s %-40s %3d/%-3d %-15s %-11s %9s %8s %s\n", a.experiment.c_str(), a.system.c_str(),
                  a.scenario.c_str(), placeText(a.x, a.y).c_str(), a.agent.c_str(), a.reached, a.tests,
                  sprintf("%d/%d/%d/%d", a.not_checked, a.what_miss, a.where_miss, a.passed).c_str(),
                  a.closest ? nameOfAction(worldOf(s), a.closest->action).c_str() : "-",
                  a.closest ? sprintf("%.5f", a.closest->what_distance).c_str() : "-",
                  a.closest ? sprintf("%.4f", a.closest->where_distance).c_str() : "-", colour.c_str());
  }
  for (const auto& [dir, why] : s.errors) out += "error: " + why + "\n";
  return out;
}

nlohmann::json byAgentJson(const ExplainSummary& s) {
  const std::vector<AgentSubGoal> agents = subGoalsByAgent(s);
  json j = {{"root", s.root}, {"tests", s.tests.size()}, {"by_system", json::array()}, {"by_agent", json::array()},
            {"errors", json::array()}};
  for (const SystemSubGoal& r : subGoalsBySystem(agents))
    j["by_system"].push_back({{"experiment", r.experiment},
                              {"system", r.system},
                              {"scenario", r.scenario},
                              {"x", r.x},
                              {"y", r.y},
                              {"agents", r.agents},
                              {"agents_always_reached", r.agents_always},
                              {"agents_never_checked", r.agents_never_checked},
                              {"agents_what_miss", r.agents_what_miss},
                              {"agents_where_miss", r.agents_where_miss},
                              {"agents_colour_blocked", r.agents_colour_blocked},
                              {"closest_what", r.closest_what},
                              {"image_match", r.planner.image_match}});
  for (const AgentSubGoal& a : agents) {
    json c = nullptr;
    if (a.closest)
      c = {{"action", nameOfAction(worldOf(s), a.closest->action)},
           {"what_distance", a.closest->what_distance},
           {"what_ok", a.closest->what_ok},
           {"where_distance", a.closest->where_distance},
           {"where_ok", a.closest->where_ok}};
    j["by_agent"].push_back({{"experiment", a.experiment},
                             {"system", a.system},
                             {"agent", a.agent},
                             {"scenario", a.scenario},
                             {"x", a.x},
                             {"y", a.y},
                             {"tests", a.tests},
                             {"reached", a.reached},
                             {"not_checked", a.not_checked},
                             {"what_miss", a.what_miss},
                             {"where_miss", a.where_miss},
                             {"passed", a.passed},
                             {"closest", c},
                             {"closest_what_max", a.closest ? json(a.closest_what_max) : json(nullptr)},
                             {"place_affordance", a.place_affordance ? json(*a.place_affordance) : json(nullptr)},
                             {"colour_action", a.colour_action >= 0 ? json(nameOfAction(worldOf(s), a.colour_action)) : json(nullptr)},
                             {"colour_blocked", a.colour_blocked}});
  }
  for (const auto& [dir, why] : s.errors) j["errors"].push_back({{"log", dir}, {"error", why}});
  return j;
}

}  // namespace afford
