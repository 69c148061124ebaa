#include "experiment/replay/explain.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <tuple>

#include "afford/processes.hpp"
#include "afford/protocol.hpp"
#include "afford/decode.hpp"
#include "afford/extrinsic_result_t.hpp"
#include "afford/forward_query_t.hpp"
#include "afford/look_t.hpp"
#include "afford/scene_t.hpp"
#include "planner/planner.hpp"

namespace afford {
namespace fs = std::filesystem;
using nlohmann::json;

bool ExplainedIteration::reached() const {
  return std::any_of(reach_checks.begin(), reach_checks.end(), [](const ExplainedReachCheck& c) { return c.reached; });
}

namespace {

std::string format(const char* fmt, ...) __attribute__((format(printf, 1, 2)));
std::string format(const char* fmt, ...) {
  va_list args;
  va_start(args, fmt);
  va_list again;
  va_copy(again, args);
  const int n = std::vsnprintf(nullptr, 0, fmt, args);
  va_end(args);
  std::string out(n > 0 ? static_cast<std::size_t>(n) : 0, '\0');
  if (n > 0) std::vsnprintf(out.data(), out.size() + 1, fmt, again);
  va_end(again);
  return out;
}

std::string actionName(int a) { return validAction(a) ? std::string(kActionNames[a]) : "action " + std::to_string(a); }

const char* kindName(PlannerKind k) { return nameOf(kPlannerKindNames, k); }
const char* metricName(PositionMetric m) { return nameOf(kPositionMetricNames, m); }

// The run's messages of one type, each serial once (a recording may hold a
// message twice: one the logger asked for again and got after all), decoded
// and checked as a receiver would; what a receiver would refuse is a warning.
template <class Msg>
std::map<std::int64_t, Msg> messages(const std::vector<LogEvent>& events, const Channel<Msg>& typed,
                                     const std::string& run_id, const BoundsContext& ctx,
                                     std::vector<std::string>& warnings) {
  const char* channel = typed.name;
  std::map<std::int64_t, Msg> out;
  int refused = 0;
  std::string first_why;
  for (const LogEvent& e : events) {
    if (e.channel != channel) continue;
    Msg m;
    std::string why;
    if (!decodeChecked(e.data.data(), e.data.size(), ctx, m, why)) {
      if (refused++ == 0) first_why = why;
      continue;
    }
    if (m.run_id != run_id) continue;
    out.emplace(m.serial, std::move(m));
  }
  if (refused > 0)
    warnings.push_back(format("%s: %d recorded message(s) refused (corrupted?), the first: %s", channel, refused,
                              first_why.c_str()));
  return out;
}

// The better of two checks against a sub-goal: one that passed both tests;
// else one whose predicted place matched (the right object and action, only
// the image off); else the smaller what-distance.
bool closerCheck(const ExplainedCheck& a, const ExplainedCheck& b) {
  if (a.passes() != b.passes()) return a.passes();
  if (a.where_ok != b.where_ok) return a.where_ok;
  return a.what_distance < b.what_distance;
}

// What the planner core tells as it replays the test (PlannerObserver): the
// iterations, the sub-goals with their images, and the core's own figures.
struct Recorder : PlannerObserver {
  std::map<std::int64_t, ExplainedIteration> steps;
  std::vector<ExplainedSubGoal> sub_goals;
  std::vector<std::vector<std::uint8_t>> images;  // of sub_goals
  std::vector<SubGoalRecord> records;             // as of the last iteration ended
  std::map<std::size_t, SubGoalExit> exits;       // of the sub-goals left unreached
  int current = -1;

  ExplainedIteration& at(int iteration) {
    auto [it, fresh] = steps.try_emplace(iteration);
    if (fresh) {
      it->second.step = iteration;
      it->second.sub_goal = current;
    }
    return it->second;
  }
  void requested(int iteration, const PlannerRequest& r) override {
    ExplainedIteration& it = at(iteration);
    if (r.kind == PlannerRequest::Forward && r.prefix.empty()) it.candidates = r.actions;
    if (r.kind == PlannerRequest::Act) {
      it.executed = r.action;
      it.target_x = r.x;
      it.target_y = r.y;
    }
  }
  void subGoalPicked(int iteration, const View& g) override {
    ExplainedSubGoal s;
    s.x = g.x;
    s.y = g.y;
    s.first_step = s.last_step = iteration;
    sub_goals.push_back(s);
    images.push_back(g.image);
    current = static_cast<int>(sub_goals.size()) - 1;
    ExplainedIteration& it = at(iteration);
    it.sub_goal = current;
    it.picked = true;
  }
  void reachChecked(int iteration, bool after_action, double distance, bool reached) override {
    at(iteration).reach_checks.push_back({after_action, distance, reached});
  }
  void objectTaken(int iteration, const View& object, const std::array<double, kNumActions>& affordance) override {
    ExplainedIteration& it = at(iteration);
    it.scanned = true;
    it.object_x = object.x;
    it.object_y = object.y;
    it.affordance = affordance;
  }
  void predictionsChecked(int iteration, const std::vector<int>& prefix,
                          const std::vector<PlannerCheck>& checks) override {
    // The checks of the multi-step search's imagined objects lead to the first action's: those are explained.
    if (prefix.empty()) at(iteration).checks = checks;
  }
  void subGoalLeft(int /*iteration*/, std::size_t sub_goal, SubGoalExit why) override { exits[sub_goal] = why; }
  void iterationEnded(int iteration, const std::vector<SubGoalRecord>& sub_goal_records) override {
    at(iteration);
    records = sub_goal_records;
  }
};

// What the replayed planner published against the recording, channel by
// channel and serial by serial; why it stopped if it did not finish.
void compareWithRecord(const ReplayedProcess& planner, const std::vector<LogEvent>& recorded, const std::string& run_id,
                       const BoundsContext& ctx, std::vector<std::string>& warn) {
  std::map<std::string, std::map<std::int64_t, const LogEvent*>> mine, theirs;
  for (const LogEvent& e : planner.published()) {
    RunHeader h;
    if (peekRunHeader(e.data.data(), static_cast<std::uint32_t>(e.data.size()), h)) mine[e.channel].emplace(h.serial, &e);
  }
  for (const LogEvent& e : recorded) {
    if (!isSerialChannel(e.channel) || publisherOf(e.channel, true) != std::string("planner")) continue;
    RunHeader h;
    if (peekRunHeader(e.data.data(), static_cast<std::uint32_t>(e.data.size()), h) && h.run_id == run_id)
      theirs[e.channel].emplace(h.serial, &e);
  }
  for (const auto& [channel, recorded_ones] : theirs) {
    const auto& replayed = mine[channel];
    for (const auto& [serial, e] : recorded_ones) {
      auto it = replayed.find(serial);
      if (it != replayed.end() && it->second->data != e->data) {
        warn.push_back(format("%s serial %lld of the replayed planner differs from the recorded one: the log is not "
                              "this planner's (another version?); what follows is the replayed planner's account",
                              channel.c_str(), static_cast<long long>(serial)));
        break;
      }
    }
  }
  if (!mine[ch::extrinsicResult.name].empty()) return;
  // It did not finish: say what it waits for that the log lacks.
  std::int32_t last_seq = -1;
  std::int64_t last_step = -1;
  bool query = false;
  for (const char* c : {ch::look.name, ch::forwardQuery.name})
    for (const auto& [serial, e] : mine[c]) {
      std::string why;
      if (c == std::string(ch::look.name)) {
        look_t l;
        if (decodeChecked(e->data.data(), e->data.size(), ctx, l, why) && l.seq > last_seq)
          std::tie(last_seq, last_step, query) = std::make_tuple(l.seq, l.step, false);
      } else {
        forward_query_t q;
        if (decodeChecked(e->data.data(), e->data.size(), ctx, q, why) && q.seq > last_seq)
          std::tie(last_seq, last_step, query) = std::make_tuple(q.seq, q.step, true);
      }
    }
  warn.push_back(last_seq < 0 ? std::string("the replayed planner made no request: the log does not start the test")
                 : query ? format("iteration %lld: FORWARD_QUERY seq %d has no FORWARD_PREDICTION in the log: the "
                                  "replayed planner stops there",
                                  static_cast<long long>(last_step), last_seq)
                         : format("iteration %lld: LOOK seq %d has no FOCUS answering it in the log (or the "
                                  "PREDICTION of its object is missing): the replayed planner stops there",
                                  static_cast<long long>(last_step), last_seq));
}

}  // namespace

namespace {

// Why a test's log without its EXTRINSIC_RESULT cannot be explained: how far it goes.
[[noreturn]] void endsBeforeTheResult(const RunEvents& run, const std::string& where, const std::string& run_id,
                                      std::int64_t torn_bytes, const std::string& incomplete, const BoundsContext& ctx,
                                      std::vector<std::string>& warn) {
  std::int64_t last_step = -1;
  for (const auto& [serial, s] : messages(run.events, ch::scene, run_id, ctx, warn)) last_step = std::max(last_step, s.step);
  for (const auto& [serial, l] : messages(run.events, ch::look, run_id, ctx, warn)) last_step = std::max(last_step, l.step);
  std::string why = where + ": the log of test '" + run_id +
                    "' ends before its EXTRINSIC_RESULT, so it does not say how the test ended (a truncated log: " +
                    std::to_string(run.events.size()) + " events, " +
                    (last_step < 0 ? std::string("the test had not begun")
                                   : "the last at planner iteration " + std::to_string(last_step));
  if (torn_bytes > 0) why += ", then an incomplete event of " + std::to_string(torn_bytes) + " bytes";
  if (!incomplete.empty()) why += "; its manifest: " + incomplete;
  throw std::runtime_error(why + ")");
}

// What is wrong with the log itself: repeated results, a torn end, an incomplete manifest, gaps.
void warnOfTheLog(const RunEvents& run, std::size_t results, std::int64_t torn_bytes, const std::string& incomplete,
                  const std::vector<LogGap>& manifest_missing, const std::string& run_id, const BoundsContext& ctx,
                  std::vector<std::string>& warn) {
  if (results > 1) warn.push_back(format("%zu EXTRINSIC_RESULT messages: the first is explained", results));
  if (torn_bytes > 0)
    warn.push_back(format("the log ends with an incomplete event (%lld bytes), after the EXTRINSIC_RESULT",
                          static_cast<long long>(torn_bytes)));
  if (!incomplete.empty()) warn.push_back("the log's manifest says it is incomplete: " + incomplete);
  std::vector<LogGap> gaps = recordingGaps(run.events, run_id, true, ctx);
  for (const LogGap& g : manifest_missing) {  // what the logger knew it never got, beyond the last recorded
    const bool known = std::any_of(gaps.begin(), gaps.end(), [&](const LogGap& h) {
      return h.channel == g.channel && h.first <= g.first && h.last >= g.last;
    });
    if (!known) gaps.push_back(g);
  }
  for (const LogGap& g : gaps)
    warn.push_back(g.first == g.last
                       ? format("%s serial %lld is missing from the log", g.channel.c_str(), static_cast<long long>(g.first))
                       : format("%s serials %lld..%lld are missing from the log", g.channel.c_str(),
                                static_cast<long long>(g.first), static_cast<long long>(g.last)));

}

// What the environment says of the scenes: the goal distance at the start and after each action.
void goalDistances(Explanation& ex, Recorder& rec, const RunEvents& run, const BoundsContext& ctx) {
  std::vector<std::string>& warn = ex.warnings;
  std::map<std::int64_t, const scene_t*> action_scene_by_step;
  const auto scenes = messages(run.events, ch::scene, ex.run_id, ctx, warn);
  for (const auto& [serial, s] : scenes) {
    if (s.cause == scene_t::CAUSE_START) ex.start_goal_distance = s.goal_distance;
    if (s.cause == scene_t::CAUSE_ACTION) action_scene_by_step.emplace(s.step, &s);
    if (s.cause == scene_t::CAUSE_START || s.cause == scene_t::CAUSE_ACTION) ex.final_goal_distance = s.goal_distance;
  }
  for (auto& [step, it] : rec.steps) {
    if (it.executed < 0) continue;
    auto s = action_scene_by_step.find(step);
    if (s != action_scene_by_step.end())
      it.goal_distance_after = s->second->goal_distance;
    else
      warn.push_back(format("iteration %lld: no SCENE after the action in the log", static_cast<long long>(step)));
  }
}

// The sub-goals: the core's own figures, what the iterations show of each, and how each ended.
// Returns the actions executed.
int explainSubGoals(Explanation& ex, const Recorder& rec, const PlannerConfig& p) {
  std::vector<std::string>& warn = ex.warnings;
  ex.sub_goals = rec.sub_goals;
  for (std::size_t i = 0; i < ex.sub_goals.size() && i < rec.records.size(); ++i) {
    const SubGoalRecord& r = rec.records[i];
    ExplainedSubGoal& g = ex.sub_goals[i];
    g.iterations = r.iterations;
    g.actions_checked = r.actions_checked;
    g.actions_taken = r.actions_taken;
    g.reached = r.reached;
  }
  int executed = 0;
  for (auto& [step, it] : rec.steps) {
    ex.steps.push_back(it);
    executed += it.executed >= 0;
    if (it.sub_goal < 0) continue;
    ExplainedSubGoal& g = ex.sub_goals[static_cast<std::size_t>(it.sub_goal)];
    g.last_step = step;
    g.reached_when_picked = g.reached_when_picked || (it.picked && !it.reach_checks.empty() && it.reach_checks.front().reached);
    for (const ExplainedCheck& c : it.checks) {
      if (!c.checked) continue;
      if (!g.closest || closerCheck(c, *g.closest)) {
        g.closest = c;
        g.closest_step = step;
      }
    }
  }
  // The object at each sub-goal's place, as the scans found it.
  for (std::size_t i = 0; i < ex.sub_goals.size(); ++i) {
    ExplainedSubGoal& g = ex.sub_goals[i];
    for (const ExplainedIteration& it : ex.steps)  // while it was the sub-goal and not yet reached
      if (it.sub_goal == static_cast<int>(i) && !it.reached() && it.scanned && it.affordance &&
          positionDistance(it.object_x, it.object_y, g.x, g.y, p.position_metric) <= p.position_match)
        g.place_affordance = it.affordance;
    if (!g.place_affordance) continue;
    std::array<double, 3> channel{};
    const std::vector<std::uint8_t>& image = rec.images[i];
    for (std::size_t b = 0; b < image.size(); ++b) channel[b % 3] += image[b];
    const int dominant = static_cast<int>(std::max_element(channel.begin(), channel.end()) - channel.begin());
    for (int a = 0; a < kNumActions; ++a)
      if (kActionChannel[static_cast<std::size_t>(a)] == dominant) g.colour_action = a;
  }
  for (std::size_t i = 0; i < ex.sub_goals.size(); ++i) {
    ExplainedSubGoal& g = ex.sub_goals[i];
    if (g.reached) {
      g.ended = "reached";
    } else if (i + 1 == ex.sub_goals.size()) {
      g.ended = "open";
    } else {  // why the core left it
      const auto exit = rec.exits.find(i);
      g.ended = exit == rec.exits.end()                       ? "open"
                : exit->second == SubGoalExit::Weighed        ? "left"
                : exit->second == SubGoalExit::NotActionable  ? "not_actionable"
                                                              : "timeout";
      if (g.ended == "timeout" && g.iterations < p.subgoal_timeout)
        warn.push_back(format("sub-goal %zu was given up after %d iterations, before planner.subgoal_timeout (%d)", i,
                              g.iterations, p.subgoal_timeout));
    }
  }
  return executed;
}

// How it ended, in the order the planner asks at the end of an iteration.
void howItEnded(Explanation& ex, const extrinsic_result_t& result, const PlannerConfig& p) {
  std::vector<std::string>& warn = ex.warnings;
  const bool out_of_budget = result.step >= p.budget;
  const bool out_of_attempts = result.attempts >= p.max_attempts;
  if (result.success) {
    ex.end = "solved";
    if (!(ex.final_goal_distance >= 0 && ex.final_goal_distance < p.success_distance))
      warn.push_back(format("the EXTRINSIC_RESULT says solved, but the last SCENE's goal distance %.6g is not below "
                            "planner.success_distance %.6g",
                            ex.final_goal_distance, p.success_distance));
  } else if (out_of_budget) {
    ex.end = "budget";
    ex.also_out_of_attempts = out_of_attempts;
  } else if (out_of_attempts) {
    ex.end = "attempts";
  } else {
    ex.end = "unknown";
    warn.push_back(format("the EXTRINSIC_RESULT says not solved after %lld of %d iterations and %d of %d actions: "
                          "neither limit was reached",
                          static_cast<long long>(result.step), p.budget, result.attempts, p.max_attempts));
  }
}

// The rebuilt figures against what the planner reported.
void compareWithResult(Explanation& ex, const extrinsic_result_t& result, int executed) {
  std::vector<std::string>& warn = ex.warnings;
  if (static_cast<std::int64_t>(ex.steps.size()) != result.step)
    warn.push_back(format("the replayed planner ran %zu iterations, the EXTRINSIC_RESULT says %lld", ex.steps.size(),
                          static_cast<long long>(result.step)));
  if (executed != result.attempts)
    warn.push_back(format("the replayed planner executed %d actions, the EXTRINSIC_RESULT says %d", executed,
                          result.attempts));
  if (ex.sub_goals.size() != result.sub_goals.size())
    warn.push_back(format("the replayed planner picked %zu sub-goals, the EXTRINSIC_RESULT says %zu", ex.sub_goals.size(),
                          result.sub_goals.size()));
  for (std::size_t i = 0; i < std::min(ex.sub_goals.size(), result.sub_goals.size()); ++i) {
    const ExplainedSubGoal& g = ex.sub_goals[i];
    const sub_goal_t& r = result.sub_goals[i];
    auto differ = [&](const char* what, long long log, long long reported) {
      if (log != reported)
        warn.push_back(format("sub-goal %zu: the replayed planner counts %s %lld, the EXTRINSIC_RESULT %lld", i, what,
                              log, reported));
    };
    if (g.x != r.x || g.y != r.y)
      warn.push_back(format("sub-goal %zu: the replayed planner places it at (%.4f, %.4f), the EXTRINSIC_RESULT at (%.4f, %.4f)", i, g.x,
                            g.y, r.x, r.y));
    differ("iterations", g.iterations, r.iterations);
    differ("actions checked", g.actions_checked, r.actions_checked);
    differ("actions taken", g.actions_taken, r.actions_taken);
    differ("reached", g.reached, r.reached);
  }
}

}  // namespace

Explanation explainRunEvents(const RunEvents& run, const std::string& where, std::int64_t torn_bytes,
                             const std::string& incomplete, const std::vector<LogGap>& manifest_missing) {
  Explanation ex;
  ex.log = where;
  ex.run_id = run.config.run_id;
  ex.experiment = run.config.experiment;
  ex.system = run.config.system;
  ex.seed = run.config.seed;
  RunConfig config;
  try {
    config = parseRunConfigText(run.config.config_yaml);
  } catch (const std::exception& e) {
    throw std::runtime_error(where + ": the configuration in the RUN_CONFIG of run '" + ex.run_id +
                             "' is refused: " + e.what());
  }
  ex.agent = fs::path(config.extrinsic_checkpoint).parent_path().filename().string();
  if (config.phase != Phase::Extrinsic || !config.scenario)
    throw NotAnExtrinsicTest(where + ": run '" + ex.run_id +
                             "' is not an extrinsic test (its RUN_CONFIG says phase: intrinsic); "
                             "explain reads the log of one extrinsic test");
  ex.scenario = config.scenario->name;
  ex.planner = config.planner;
  const PlannerConfig& p = config.planner;
  const BoundsContext ctx{&config.protocol, &config};
  std::vector<std::string>& warn = ex.warnings;

  const auto results = messages(run.events, ch::extrinsicResult, ex.run_id, ctx, warn);
  if (results.empty()) endsBeforeTheResult(run, where, ex.run_id, torn_bytes, incomplete, ctx, warn);
  const extrinsic_result_t& result = results.begin()->second;
  warnOfTheLog(run, results.size(), torn_bytes, incomplete, manifest_missing, ex.run_id, ctx, warn);
  ex.success = result.success;
  ex.completion = result.completion;
  ex.attempts = result.attempts;
  ex.utility = result.utility;
  ex.iterations = result.step;

  // The test replayed into a fresh planner, whose core tells what it checks and decides.
  Recorder rec;
  HostOptions host;
  host.single_thread = true;
  host.log_root = "";  // the planner reads no file
  host.planner_observer = &rec;
  ReplayedProcess planner("planner", config.protocol, /*extrinsic=*/true, host);
  for (const LogEvent& e : run.events) planner.feed(e);
  compareWithRecord(planner, run.events, ex.run_id, ctx, warn);
  goalDistances(ex, rec, run, ctx);
  const int executed = explainSubGoals(ex, rec, p);
  howItEnded(ex, result, p);
  compareWithResult(ex, result, executed);
  return ex;
}

Explanation explainLog(const std::string& log_path, const std::string& run_id, spdlog::logger& log) {
  if (!fs::exists(log_path)) throw std::runtime_error("no such log folder or file: " + log_path);
  RecordedLog recorded = readRecordedLog(log_path, log);
  if (recorded.events.empty())
    throw std::runtime_error(log_path + ": the log holds no complete event" +
                             (recorded.torn_bytes > 0 ? " (" + std::to_string(recorded.torn_bytes) +
                                                            " bytes that are not one: a truncated or not an LCM log)"
                                                      : std::string()));
  std::vector<LogGap> missing;
  const std::string incomplete = manifestIncomplete(log_path, missing);
  const RunEvents run = runEventsOf(std::move(recorded.events), run_id, log_path, log);
  return explainRunEvents(run, log_path, recorded.torn_bytes, incomplete, missing);
}

bool ExplainedSubGoal::colourActionBlocked(const PlannerConfig& p) const {
  return p.restrict_by_affordance && place_affordance && colour_action >= 0 &&
         (*place_affordance)[static_cast<std::size_t>(colour_action)] <= p.affordance_threshold;
}

// ---- text ---------------------------------------------------------------------------

namespace {

std::string endText(const Explanation& e) {
  const PlannerConfig& p = e.planner;
  if (e.end == "solved")
    return format("solved at iteration %d (counted from 1): the goal distance %.3g fell below planner.success_distance %.3g",
                  e.completion, e.final_goal_distance, p.success_distance);
  if (e.end == "budget")
    return format("not solved: the budget of %d iterations ran out (planner.budget)%s", p.budget,
                  e.also_out_of_attempts ? format(", and the %d actions of planner.max_attempts with it", p.max_attempts).c_str()
                                         : "");
  if (e.end == "attempts")
    return format("not solved: the %d executed actions of planner.max_attempts ran out, after %lld of %d iterations",
                  p.max_attempts, static_cast<long long>(e.iterations), p.budget);
  return "not solved, and neither the budget nor the action limit was reached (see the warnings)";
}

std::string subGoalText(const Explanation& e, std::size_t i) {
  const ExplainedSubGoal& g = e.sub_goals[i];
  std::string how;
  if (g.reached_when_picked)
    how = format("reached already when picked, at iteration %lld", static_cast<long long>(g.first_step));
  else if (g.ended == "reached")
    how = format("reached at iteration %lld", static_cast<long long>(g.last_step));
  else if (g.ended == "timeout")
    how = format("not reached: abandoned after %d iterations (planner.subgoal_timeout %d)", g.iterations,
                 e.planner.subgoal_timeout);
  else if (g.ended == "left")
    how = "not reached: left after weighing an action (Algorithm 3)";
  else if (g.ended == "not_actionable")
    how = format("not reached: no remembered object was left to try for it, after %d iterations (top-down attention)",
                 g.iterations);
  else
    how = "not reached: the test ended with it";
  return format("  #%zu at (%.4f, %.4f), iterations %lld..%lld: %d spent, %d actions checked, %d taken; %s", i, g.x, g.y,
                static_cast<long long>(g.first_step), static_cast<long long>(g.last_step), g.iterations,
                g.actions_checked, g.actions_taken, how.c_str());
}

std::string closestText(const ExplainedSubGoal& g, const PlannerConfig& p) {
  if (!g.closest) return "no action was checked";
  const ExplainedCheck& c = *g.closest;
  // An action that passed both thresholds is no miss: the sub-goal was lost
  // after it (the action failed, or the utility planner did not take it).
  return format("%s: %s at iteration %lld, what %.5f (%s %.5f), where %.4f (%s %.4f)",
                c.passes() ? "passed" : "closest", actionName(c.action).c_str(),
                static_cast<long long>(g.closest_step), c.what_distance, c.what_ok ? "<" : "not <", p.image_match,
                c.where_distance, c.where_ok ? "<=" : "not <=", p.position_match);
}

}  // namespace

std::string explanationText(const Explanation& e) {
  const PlannerConfig& p = e.planner;
  std::string out;
  out += format("test %s: scenario %s, %s planner (Algorithm %d), %s agent of experiment %s, seed %lld\n", e.run_id.c_str(),
                e.scenario.c_str(), kindName(p.kind), p.kind == PlannerKind::Utility ? 3 : 2, e.system.c_str(),
                e.experiment.c_str(), static_cast<long long>(e.seed));
  out += "  " + endText(e) + "\n";
  out += format("  %lld iterations, %d actions taken, utility %.3g; goal distance %.3g at the start, %.3g at the end\n",
                static_cast<long long>(e.iterations), e.attempts, e.utility, e.start_goal_distance, e.final_goal_distance);
  out += format("  thresholds: what-distance < %.5g (planner.image_match), where-distance (%s) <= %.5g "
                "(planner.position_match), sub-goal reached < %.5g (planner.subgoal_match), sub-goal timeout %d "
                "iterations",
                p.image_match, metricName(p.position_metric), p.position_match, p.subgoal_match, p.subgoal_timeout);
  if (p.restrict_by_affordance) out += format(", actions checked if afforded > %.3g", p.affordance_threshold);
  out += "\n";
  out += format("sub-goals (%zu):\n", e.sub_goals.size());
  for (std::size_t i = 0; i < e.sub_goals.size(); ++i) {
    out += subGoalText(e, i) + "\n";
    if (!e.sub_goals[i].reached) out += "      " + closestText(e.sub_goals[i], p) + "\n";
    const ExplainedSubGoal& g = e.sub_goals[i];
    if (g.place_affordance && g.colour_action >= 0)
      out += format("      the object at its place: %s afforded %.3f%s\n", actionName(g.colour_action).c_str(),
                    (*g.place_affordance)[static_cast<std::size_t>(g.colour_action)],
                    g.colourActionBlocked(p) ? format(" (not above %.3g: never asked about)", p.affordance_threshold).c_str()
                                              : "");
  }
  out += "iterations:\n";
  for (const ExplainedIteration& it : e.steps) {
    out += format("  [%lld] ", static_cast<long long>(it.step));
    if (it.sub_goal < 0)
      out += "no sub-goal known\n";
    else if (it.picked)
      out += format("sub-goal #%d picked at (%.4f, %.4f)\n", it.sub_goal, e.sub_goals[static_cast<std::size_t>(it.sub_goal)].x,
                    e.sub_goals[static_cast<std::size_t>(it.sub_goal)].y);
    else
      out += format("sub-goal #%d\n", it.sub_goal);
    auto reach = [&](const ExplainedReachCheck& c) {
      out += format("      scene at the sub-goal%s: distance %.5f, %s\n", c.after_action ? " after the action" : "",
                    c.distance, c.reached ? "reached" : "not reached");
    };
    for (const ExplainedReachCheck& c : it.reach_checks)
      if (!c.after_action) reach(c);
    if (it.scanned) {
      out += format("      object at (%.4f, %.4f)", it.object_x, it.object_y);
      if (it.affordance) {
        out += ", affordances:";
        for (int a = 0; a < kNumActions; ++a)
          out += format("%s %s %.3f", a ? "," : "", actionName(a).c_str(), (*it.affordance)[static_cast<std::size_t>(a)]);
      }
      out += "\n";
      if (it.candidates.empty()) out += "      no action afforded: nothing checked\n";
    }
    for (const ExplainedCheck& c : it.checks)
      out += format("      %-10s what %.5f %s %.5g %s, where %.4f %s %.5g %s%s\n", actionName(c.action).c_str(),
                    c.what_distance, c.what_ok ? "<" : ">=", p.image_match, c.what_ok ? "ok" : "no", c.where_distance,
                    c.where_ok ? "<=" : ">", p.position_match, c.where_ok ? "ok" : "no",
                    !c.checked ? "  (not compared: an earlier action passed)" : c.passes() ? "  <- passes" : "");
    if (it.executed >= 0) {
      out += format("      executed: %s", actionName(it.executed).c_str());
      if (it.executed == kMove) out += format(" to (%.4f, %.4f)", it.target_x, it.target_y);
      out += format("; goal distance after: %.3g\n", it.goal_distance_after);
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
  auto check = [](const ExplainedCheck& c) {
    return json{{"action", c.action},         {"action_name", actionName(c.action)}, {"what_distance", c.what_distance},
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
    s["colour_action"] = g.colour_action >= 0 ? json(actionName(g.colour_action)) : json(nullptr);
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
                       {"action_name", actionName(it.executed)},
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

bool holdsLcm(const fs::path& dir) {
  std::error_code ec;
  for (const auto& f : fs::directory_iterator(dir, ec))
    if (f.path().extension() == ".lcm") return true;
  return false;
}

// The phase a log folder's manifest names ("" without a readable one): an
// intrinsic run's log (tens of MB) need not be read to be skipped.
std::string manifestPhase(const fs::path& dir) {
  std::ifstream in(dir / "manifest.json");
  if (!in) return "";
  const json m = json::parse(in, nullptr, false);
  if (m.is_discarded() || !m.contains("config_yaml") || !m["config_yaml"].is_string()) return "";
  try {
    const YAML::Node c = YAML::Load(m["config_yaml"].get<std::string>());
    return c["phase"] ? c["phase"].as<std::string>() : "";
  } catch (const std::exception&) {
    return "";
  }
}

}  // namespace

bool isLogRoot(const std::string& path) {
  if (!fs::is_directory(path) || holdsLcm(path)) return false;
  std::error_code ec;
  for (const auto& f : fs::directory_iterator(path, ec))
    if (f.is_directory() && holdsLcm(f.path())) return true;
  return false;
}

ExplainSummary explainLogRoot(const std::string& root, spdlog::logger& log) {
  ExplainSummary s;
  s.root = root;
  std::vector<fs::path> dirs;
  for (const auto& f : fs::directory_iterator(root))
    if (f.is_directory() && holdsLcm(f.path())) dirs.push_back(f.path());
  std::sort(dirs.begin(), dirs.end());
  for (const fs::path& d : dirs) {
    const std::string phase = manifestPhase(d);
    if (!phase.empty() && phase != "extrinsic") {
      s.skipped.emplace_back(d.string(), "phase " + phase);
      continue;
    }
    try {
      s.tests.push_back(explainLog(d.string(), "", log));
    } catch (const NotAnExtrinsicTest& e) {
      s.skipped.emplace_back(d.string(), e.what());
    } catch (const std::exception& e) {
      s.errors.emplace_back(d.string(), e.what());
    }
  }
  if (s.tests.empty() && s.errors.empty())
    throw std::runtime_error(root + ": no extrinsic test log in it (" + std::to_string(s.skipped.size()) +
                             " other run log(s)); run the experiment with --extrinsic-reps and --keep-logs all");
  return s;
}

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
    out += format("%s%s %d", out.empty() ? "" : ", ", end, n);
  }
  return out + format(" (%d tests)", total);
}

}  // namespace

std::string summaryText(const ExplainSummary& s) {
  std::string out = format("%zu extrinsic test(s) under %s", s.tests.size(), s.root.c_str());
  if (!s.skipped.empty()) out += format(" (%zu other run log(s) skipped)", s.skipped.size());
  out += "\n";
  out += format("%-44s %-6s %-12s %-8s %-9s %10s %8s %7s %9s %8s\n", "test", "system", "scenario", "planner", "end",
                "completion", "actions", "utility", "sub-goals", "warnings");
  for (const Explanation& t : s.tests) {
    int reached = 0;
    for (const auto& g : t.sub_goals) reached += g.reached;
    out += format("%-44s %-6s %-12s %-8s %-9s %10d %8d %7.3g %4d/%-4zu %8zu\n", t.run_id.c_str(), t.system.c_str(),
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
      out += format("  %s #%zu at (%.4f, %.4f), %s: %s\n", t.run_id.c_str(), i, g.x, g.y, g.ended.c_str(),
                    closestText(g, t.planner).c_str());
    }
    if (missed == 0)
      out += format("  %s: every sub-goal it picked was reached; it ended by %s before it picked another\n",
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

}  // namespace afford

namespace afford {

// ---- per agent and sub-goal -----------------------------------------------------------

std::vector<AgentSubGoal> subGoalsByAgent(const ExplainSummary& s) {
  using Key = std::tuple<std::string, std::string, std::string, double, double, std::string>;
  std::map<Key, AgentSubGoal> rows;
  for (const Explanation& t : s.tests) {
    // A sub-goal picked again in the same test (after a timeout) counts once:
    // reached if any pick reached it, with the best check of all its picks.
    std::map<std::pair<double, double>, ExplainedSubGoal> merged;
    std::map<std::pair<double, double>, bool> blocked;
    for (const ExplainedSubGoal& g : t.sub_goals) {
      auto [it, fresh] = merged.try_emplace({g.x, g.y}, g);
      ExplainedSubGoal& m = it->second;
      bool& b = blocked[{g.x, g.y}];
      b = b || g.colourActionBlocked(t.planner);
      if (fresh) continue;
      m.reached = m.reached || g.reached;
      if (g.closest && (!m.closest || closerCheck(*g.closest, *m.closest))) m.closest = g.closest;
      if (g.place_affordance) {
        m.place_affordance = g.place_affordance;
        m.colour_action = g.colour_action;
      }
    }
    for (const auto& [place, g] : merged) {
      AgentSubGoal& r = rows[Key{t.experiment, t.system, t.scenario, g.x, g.y, t.agent}];
      if (r.tests == 0) {
        r.experiment = t.experiment, r.system = t.system, r.agent = t.agent, r.scenario = t.scenario;
        r.x = g.x, r.y = g.y;
        r.planner = t.planner;
      }
      ++r.tests;
      r.reached += g.reached;
      if (!g.reached) {
        if (!g.closest)
          ++r.not_checked;
        else if (g.closest->passes())
          ++r.passed;
        else if (!g.closest->what_ok)
          ++r.what_miss;
        else
          ++r.where_miss;
      }
      if (g.closest) {
        if (!r.closest || closerCheck(*g.closest, *r.closest)) r.closest = g.closest;
        r.closest_what_max = std::max(r.closest_what_max, g.closest->what_distance);
      }
      if (g.place_affordance) {
        r.place_affordance = g.place_affordance;
        r.colour_action = g.colour_action;
      }
      r.colour_blocked += !g.reached && blocked[place];
    }
  }
  std::vector<AgentSubGoal> out;
  for (auto& [key, r] : rows) out.push_back(std::move(r));
  return out;
}

std::vector<SystemSubGoal> subGoalsBySystem(const std::vector<AgentSubGoal>& agents) {
  std::vector<SystemSubGoal> out;
  for (const AgentSubGoal& a : agents) {  // ordered: one system's sub-goal's agents are adjacent
    if (out.empty() || out.back().experiment != a.experiment || out.back().system != a.system ||
        out.back().scenario != a.scenario || out.back().x != a.x || out.back().y != a.y) {
      out.emplace_back();
      SystemSubGoal& n = out.back();
      n.experiment = a.experiment, n.system = a.system, n.scenario = a.scenario, n.x = a.x, n.y = a.y;
      n.planner = a.planner;
    }
    SystemSubGoal& r = out.back();
    ++r.agents;
    r.agents_always += a.reached == a.tests;
    r.agents_never_checked += !a.closest;
    if (a.closest) {
      r.agents_what_miss += !a.closest->what_ok;
      r.agents_where_miss += a.closest->what_ok && !a.closest->where_ok;
      r.closest_what.insert(std::upper_bound(r.closest_what.begin(), r.closest_what.end(), a.closest->what_distance),
                            a.closest->what_distance);
    }
    r.agents_colour_blocked += a.colour_blocked > 0;
  }
  return out;
}

namespace {

std::string placeText(double x, double y) { return format("(%.3f, %.3f)", x, y); }

double median(const std::vector<double>& sorted) {
  const std::size_t n = sorted.size();
  return n % 2 ? sorted[n / 2] : (sorted[n / 2 - 1] + sorted[n / 2]) / 2;
}

}  // namespace

std::string byAgentText(const ExplainSummary& s) {
  const std::vector<AgentSubGoal> agents = subGoalsByAgent(s);
  const std::vector<SystemSubGoal> systems = subGoalsBySystem(agents);
  std::string out = format("%zu extrinsic test(s) under %s, by system, scenario and sub-goal\n", s.tests.size(), s.root.c_str());
  out += "closest: each agent's best check over its tests (one that passed; else, of those whose predicted place\n"
         "matched, the smallest what-distance; else the smallest what-distance); a miss is a closest check not below\n"
         "planner.image_match (what) or not within planner.position_match (where); blocked: the\n"
         "colour action the object at the sub-goal's place needs was not above planner.affordance_threshold\n\n";
  out += format("%-16s %-6s %-12s %-16s %6s %6s %10s %10s %10s %5s %6s %8s\n", "experiment", "system", "scenario", "sub-goal",
                "agents", "always", "closest", "median", "max", "what", "where", "blocked");
  for (const SystemSubGoal& r : systems) {
    const bool any = !r.closest_what.empty();
    out += format("%-16s %-6s %-12s %-16s %6d %6d %10s %10s %10s %5d %6d %8d\n", r.experiment.c_str(), r.system.c_str(),
                  r.scenario.c_str(), placeText(r.x, r.y).c_str(), r.agents, r.agents_always,
                  any ? format("%.5f", r.closest_what.front()).c_str() : "-",
                  any ? format("%.5f", median(r.closest_what)).c_str() : "-",
                  any ? format("%.5f", r.closest_what.back()).c_str() : "-", r.agents_what_miss, r.agents_where_miss,
                  r.agents_colour_blocked);
  }
  out += "\nper agent (reached k/n; the causes in the tests that did not reach it: no check, what miss, where miss,\n"
         "passed both; the closest check over its tests; the place's colour action and its affordance):\n";
  out += format("%-16s %-6s %-12s %-16s %-40s %7s %-15s %-11s %9s %8s %s\n", "experiment", "system", "scenario", "sub-goal",
                "agent", "reached", "causes n/w/p/b", "closest", "what", "where", "colour action");
  for (const AgentSubGoal& a : agents) {
    std::string colour = "-";
    if (a.place_affordance && a.colour_action >= 0)
      colour = format("%s %.3f%s", actionName(a.colour_action).c_str(),
                      (*a.place_affordance)[static_cast<std::size_t>(a.colour_action)],
                      a.colour_blocked ? format(" blocked in %d", a.colour_blocked).c_str() : "");
    out += format("%-16s %-6s %-12s %-16s %-40s %3d/%-3d %-15s %-11s %9s %8s %s\n", a.experiment.c_str(), a.system.c_str(),
                  a.scenario.c_str(), placeText(a.x, a.y).c_str(), a.agent.c_str(), a.reached, a.tests,
                  format("%d/%d/%d/%d", a.not_checked, a.what_miss, a.where_miss, a.passed).c_str(),
                  a.closest ? actionName(a.closest->action).c_str() : "-",
                  a.closest ? format("%.5f", a.closest->what_distance).c_str() : "-",
                  a.closest ? format("%.4f", a.closest->where_distance).c_str() : "-", colour.c_str());
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
      c = {{"action", actionName(a.closest->action)},
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
                             {"colour_action", a.colour_action >= 0 ? json(actionName(a.colour_action)) : json(nullptr)},
                             {"colour_blocked", a.colour_blocked}});
  }
  for (const auto& [dir, why] : s.errors) j["errors"].push_back({{"log", dir}, {"error", why}});
  return j;
}

}  // namespace afford
