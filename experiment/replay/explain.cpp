#include "experiment/replay/explain.hpp"

#include <fmt/printf.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <tuple>

#include "experiment/run/outcome.hpp"
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
using fmt::sprintf;
using nlohmann::json;

bool ExplainedIteration::reached() const {
  return std::any_of(reach_checks.begin(), reach_checks.end(), [](const ExplainedReachCheck& c) { return c.reached; });
}

namespace {

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
    warnings.push_back(sprintf("%s: %d recorded message(s) refused (corrupted?), the first: %s", channel, refused,
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
    if (!isSerialChannel(e.channel) || publisherOf(e.channel, Phase::Extrinsic) != std::string("planner")) continue;
    RunHeader h;
    if (peekRunHeader(e.data.data(), static_cast<std::uint32_t>(e.data.size()), h) && h.run_id == run_id)
      theirs[e.channel].emplace(h.serial, &e);
  }
  for (const auto& [channel, recorded_ones] : theirs) {
    const auto& replayed = mine[channel];
    for (const auto& [serial, e] : recorded_ones) {
      auto it = replayed.find(serial);
      if (it != replayed.end() && it->second->data != e->data) {
        warn.push_back(sprintf("%s serial %lld of the replayed planner differs from the recorded one: the log is not "
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
                 : query ? sprintf("iteration %lld: FORWARD_QUERY seq %d has no FORWARD_PREDICTION in the log: the "
                                  "replayed planner stops there",
                                  static_cast<long long>(last_step), last_seq)
                         : sprintf("iteration %lld: LOOK seq %d has no FOCUS answering it in the log (or the "
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
  if (results > 1) warn.push_back(sprintf("%zu EXTRINSIC_RESULT messages: the first is explained", results));
  if (torn_bytes > 0)
    warn.push_back(sprintf("the log ends with an incomplete event (%lld bytes), after the EXTRINSIC_RESULT",
                          static_cast<long long>(torn_bytes)));
  if (!incomplete.empty()) warn.push_back("the log's manifest says it is incomplete: " + incomplete);
  std::vector<LogGap> gaps = recordingGaps(run.events, run_id, Phase::Extrinsic, ctx);
  for (const LogGap& g : manifest_missing) {  // what the logger knew it never got, beyond the last recorded
    const bool known = std::any_of(gaps.begin(), gaps.end(), [&](const LogGap& h) {
      return h.channel == g.channel && h.first <= g.first && h.last >= g.last;
    });
    if (!known) gaps.push_back(g);
  }
  for (const LogGap& g : gaps)
    warn.push_back(g.first == g.last
                       ? sprintf("%s serial %lld is missing from the log", g.channel.c_str(), static_cast<long long>(g.first))
                       : sprintf("%s serials %lld..%lld are missing from the log", g.channel.c_str(),
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
      warn.push_back(sprintf("iteration %lld: no SCENE after the action in the log", static_cast<long long>(step)));
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
        warn.push_back(sprintf("sub-goal %zu was given up after %d iterations, before planner.subgoal_timeout (%d)", i,
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
      warn.push_back(sprintf("the EXTRINSIC_RESULT says solved, but the last SCENE's goal distance %.6g is not below "
                            "planner.success_distance %.6g",
                            ex.final_goal_distance, p.success_distance));
  } else if (out_of_budget) {
    ex.end = "budget";
    ex.also_out_of_attempts = out_of_attempts;
  } else if (out_of_attempts) {
    ex.end = "attempts";
  } else {
    ex.end = "unknown";
    warn.push_back(sprintf("the EXTRINSIC_RESULT says not solved after %lld of %d iterations and %d of %d actions: "
                          "neither limit was reached",
                          static_cast<long long>(result.step), p.budget, result.attempts, p.max_attempts));
  }
}

// The rebuilt figures against what the planner reported.
void compareWithResult(Explanation& ex, const extrinsic_result_t& result, int executed) {
  std::vector<std::string>& warn = ex.warnings;
  if (static_cast<std::int64_t>(ex.steps.size()) != result.step)
    warn.push_back(sprintf("the replayed planner ran %zu iterations, the EXTRINSIC_RESULT says %lld", ex.steps.size(),
                          static_cast<long long>(result.step)));
  if (executed != result.attempts)
    warn.push_back(sprintf("the replayed planner executed %d actions, the EXTRINSIC_RESULT says %d", executed,
                          result.attempts));
  if (ex.sub_goals.size() != result.sub_goals.size())
    warn.push_back(sprintf("the replayed planner picked %zu sub-goals, the EXTRINSIC_RESULT says %zu", ex.sub_goals.size(),
                          result.sub_goals.size()));
  for (std::size_t i = 0; i < std::min(ex.sub_goals.size(), result.sub_goals.size()); ++i) {
    const ExplainedSubGoal& g = ex.sub_goals[i];
    const sub_goal_t& r = result.sub_goals[i];
    auto differ = [&](const char* what, long long log, long long reported) {
      if (log != reported)
        warn.push_back(sprintf("sub-goal %zu: the replayed planner counts %s %lld, the EXTRINSIC_RESULT %lld", i, what,
                              log, reported));
    };
    if (g.x != r.x || g.y != r.y)
      warn.push_back(sprintf("sub-goal %zu: the replayed planner places it at (%.4f, %.4f), the EXTRINSIC_RESULT at (%.4f, %.4f)", i, g.x,
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
  ex.world = config.world.kind;
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
  ReplayedProcess planner("planner", config.protocol, Phase::Extrinsic, host);
  for (const LogEvent& e : run.events)
    if (!isStop(e, ctx)) planner.feed(e);
  for (const LogEvent& e : run.events)  // the STOP last: the logger takes late messages after it too
    if (isStop(e, ctx)) planner.feed(e);
  compareWithRecord(planner, run.events, ex.run_id, ctx, warn);
  goalDistances(ex, rec, run, ctx);
  const int executed = explainSubGoals(ex, rec, p);
  howItEnded(ex, result, p);
  compareWithResult(ex, result, executed);
  return ex;
}

Explanation explainLog(const std::string& log_path, const std::string& run_id, spdlog::logger& log,
                       const BusKey* key) {
  if (!fs::exists(log_path)) throw std::runtime_error("no such log folder or file: " + log_path);
  const RunEvents run = readRunEvents(log_path, run_id, log, key);
  // A log cut short is not the whole test: no verdict on it, only what is missing.
  const std::string cut = run.cut.empty() ? "" : "; the log is cut: " + joinedCut(run.cut);
  std::vector<LogGap> missing;
  const std::string incomplete = manifestIncomplete(log_path, missing);
  Explanation ex;
  try {
    ex = explainRunEvents(run, log_path, run.torn_bytes, incomplete, missing);
  } catch (const NotAnExtrinsicTest&) {
    throw;
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(e.what() + cut);
  }
  if (!cut.empty()) throw std::runtime_error(log_path + ": explain gives no verdict on a part of a test" + cut);
  return ex;
}

bool ExplainedSubGoal::colourActionBlocked(const PlannerConfig& p) const {
  return p.restrict_by_affordance && place_affordance && colour_action >= 0 &&
         (*place_affordance)[static_cast<std::size_t>(colour_action)] <= p.affordance_threshold;
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
  const json m = readManifest(dir / "manifest.json");
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

ExplainSummary explainLogRoot(const std::string& root, spdlog::logger& log, const BusKey* key) {
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
      s.tests.push_back(explainLog(d.string(), "", log, key));
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

}  // namespace afford
