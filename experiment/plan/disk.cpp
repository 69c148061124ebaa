#include "experiment/plan/disk.hpp"

#include <algorithm>
#include <cstdio>

#include "afford/config.hpp"
#include "afford/forward_prediction_t.hpp"
#include "afford/forward_query_t.hpp"
#include "afford/goal_result_t.hpp"
#include "afford/image.hpp"
#include "afford/look_t.hpp"
#include "afford/protocol.hpp"
#include "environment/environment.hpp"
#include "eye/messages.hpp"
#include "motivation/messages.hpp"
#include "predictors/messages.hpp"
#include "predictors/predictors.hpp"

namespace afford {

namespace {

// LCM's log event: a sync word, an event number, a time stamp, the channel's and the data's lengths, the channel.
std::uint64_t eventBytes(const std::string& channel, std::uint64_t data) { return 4 + 8 + 8 + 4 + 4 + channel.size() + data; }

// Bytes one intrinsic step adds to the run's log, at most: its focus, prediction and decision, a scene and an
// effect (an action at every step), and its share of the affordance tables.
std::uint64_t stepBytes(const RunConfig& c, const std::string& run_id) {
  const int side = c.eye.focus_side;
  Focus f;
  f.image.assign(3u * static_cast<std::size_t>(side) * side, 0);
  focus_t focus = focusMessage(run_id, c.steps, f, focus_t::SCENE_SCAN, 0, side);
  scene_t scene{};
  scene.run_id = run_id;
  scene.data = encodeScene(Environment(c).render());
  scene.size = static_cast<int32_t>(scene.data.size());
  scene.n_objects = 0;
  Effect e;
  e.before = e.after = f;
  effect_t effect = effectMessage(run_id, scene, e, side);
  Prediction p;
  trained_t t;
  t.run_id = run_id;
  prediction_t prediction = predictionMessage(run_id, focus, p, t);
  decision_t decision = decisionMessage(run_id, prediction, Decision{});
  affordance_table_t table{};
  table.run_id = run_id;
  table.n_actions = kNumActions;
  table.affordance.assign(c.world.objects.size(), std::vector<double>(kNumActions, 0.0));
  table.n_objects = static_cast<int32_t>(table.affordance.size());
  const std::uint64_t tables = c.curve_interval > 0 ? 1 : 0;
  return eventBytes(ch::focus.name, static_cast<std::uint64_t>(focus.getEncodedSize())) +
         eventBytes(ch::prediction.name, static_cast<std::uint64_t>(prediction.getEncodedSize())) +
         eventBytes(ch::decision.name, static_cast<std::uint64_t>(decision.getEncodedSize())) +
         eventBytes(ch::scene.name, static_cast<std::uint64_t>(scene.getEncodedSize())) +
         eventBytes(ch::effect.name, static_cast<std::uint64_t>(effect.getEncodedSize())) +
         tables * eventBytes(ch::affordanceTable.name, static_cast<std::uint64_t>(table.getEncodedSize())) /
             static_cast<std::uint64_t>(std::max<std::int64_t>(1, c.curve_interval));
}

// Bytes a step of the goals phase adds to those, at most. Up to three goals end at a step (two found reached
// as they are set, then one pursued), each with its GOAL, GOAL_RESULT and a look at its place; the pursued
// one's object attended and its place looked at again after the action: five LOOKs and FOCUSes, one of them
// the step's object focus counted above. The planner's search: 1 + A + ... + A^(depth-1) forward queries
// (at most planner.search.max_queries), each answered with a predicted image of floats per action.
std::uint64_t goalsStepBytes(const RunConfig& c, const std::string& run_id) {
  const int side = c.eye.focus_side;
  const std::size_t image = 3u * static_cast<std::size_t>(side) * static_cast<std::size_t>(side);
  Focus f;
  f.image.assign(image, 0);
  const focus_t focus = focusMessage(run_id, c.steps, f, focus_t::SCENE_AT, 0, side);
  look_t look;
  look.run_id = run_id;
  Goal g;
  g.image.assign(image, 0);
  const goal_t goal = goalMessage(run_id, c.steps, 0, g, c.goals.budget);
  goal_result_t result{};
  result.run_id = run_id;
  const int depth = std::max(1, c.planner.max_depth);
  forward_query_t query;
  query.run_id = run_id;
  query.image.assign(image, 0);
  query.size = static_cast<int32_t>(image);
  query.actions.assign(kNumActions, 0);
  query.n_actions = kNumActions;
  query.prefix.assign(static_cast<std::size_t>(depth - 1), 0);
  query.n_prefix = static_cast<int8_t>(depth - 1);
  forward_prediction_t answer;
  answer.run_id = run_id;
  answer.n_actions = kNumActions;
  answer.actions.assign(kNumActions, 0);
  answer.size = static_cast<int32_t>(image);
  answer.what.assign(kNumActions, std::vector<float>(image, 0.0f));
  answer.where_x.assign(kNumActions, 0.0);
  answer.where_y.assign(kNumActions, 0.0);
  answer.n_input = kNumActions;
  answer.input_affordance.assign(kNumActions, 0.0);
  std::uint64_t queries = 0, level = 1;
  for (int d = 0; d < depth; ++d, level *= kNumActions) queries += level;
  if (c.planner.max_queries > 0) queries = std::min<std::uint64_t>(queries, static_cast<std::uint64_t>(c.planner.max_queries));
  constexpr std::uint64_t kGoals = 3, kLooks = 5;
  return kLooks * eventBytes(ch::look.name, static_cast<std::uint64_t>(look.getEncodedSize())) +
         (kLooks - 1) * eventBytes(ch::focus.name, static_cast<std::uint64_t>(focus.getEncodedSize())) +
         kGoals * (eventBytes(ch::goal.name, static_cast<std::uint64_t>(goal.getEncodedSize())) +
                   eventBytes(ch::goalResult.name, static_cast<std::uint64_t>(result.getEncodedSize()))) +
         queries * (eventBytes(ch::forwardQuery.name, static_cast<std::uint64_t>(query.getEncodedSize())) +
                    eventBytes(ch::forwardPrediction.name, static_cast<std::uint64_t>(answer.getEncodedSize())));
}

}  // namespace

DiskNeed diskNeed(const std::vector<PlannedRun>& runs, int jobs) {
  DiskNeed need;
  std::vector<std::uint64_t> snapshots;  // each intrinsic run's, while it goes
  for (const PlannedRun& r : runs) {
    if (r.spec.extrinsic) continue;
    const RunConfig c = parseRunConfigText(r.spec.config_yaml);
    const std::uint64_t step =
        stepBytes(c, r.spec.run_id) + (c.phase == Phase::Goals ? goalsStepBytes(c, r.spec.run_id) : 0);
    need.log_step = std::max(need.log_step, step);
    need.longest = std::max(need.longest, c.steps);
    if (r.keep_log) {
      need.logs += step * static_cast<std::uint64_t>(c.steps);
      ++need.kept_logs;
    }
    // The predictors' state: their forward models, the same whatever the affordance component (one's own is
    // not run for an estimate).
    const std::uint64_t weights = Predictors::forwardModelBytes(c.eye.focus_side, c.world.kind);
    if (!c.checkpoint.empty() && r.keep_checkpoint) need.checkpoints += weights;
    // Snapshots, once the run is past its first: every process's state (the predictors' weights), and what
    // each holds of what it published since its readers' latest (a snapshot's worth of steps, twice).
    const std::int64_t every = c.protocol.recovery.snapshot_steps;
    if (every > 0 && c.steps > every)
      snapshots.push_back(weights + std::min<std::uint64_t>(2 * step * static_cast<std::uint64_t>(every),
                                                              4ull * (static_cast<std::uint64_t>(c.protocol.recovery.history_mb) << 20)));
  }
  std::sort(snapshots.rbegin(), snapshots.rend());
  for (std::size_t i = 0; i < snapshots.size() && i < static_cast<std::size_t>(std::max(1, jobs)); ++i)
    need.snapshots += snapshots[i];
  return need;
}

std::string bytesText(std::uint64_t bytes) {
  char out[32];
  const double b = static_cast<double>(bytes);
  if (b >= 1e9)
    std::snprintf(out, sizeof out, "%.1f GB", b / 1e9);
  else if (b >= 1e6)
    std::snprintf(out, sizeof out, "%.0f MB", b / 1e6);
  else
    std::snprintf(out, sizeof out, "%.0f KB", b / 1e3);
  return out;
}

std::string diskLine(const DiskNeed& need) {
  std::string line = "disk: at most " + bytesText(need.total()) + ": ";
  line += need.kept_logs ? bytesText(need.logs) + " of logs (" + std::to_string(need.kept_logs) + " kept, " +
                               bytesText(need.log_step) + " a step at most)"
                         : std::string("no logs kept");
  line += ", " + bytesText(need.checkpoints) + " of checkpoints";
  if (need.snapshots) line += ", " + bytesText(need.snapshots) + " of snapshots while runs go (removed at their end)";
  return line;
}

std::string diskWarning(const DiskNeed& need, std::uint64_t free_bytes, const std::string& where) {
  if (need.total() <= free_bytes) return "";
  return "the experiment may write up to " + bytesText(need.total()) + ", and " + where + " has " +
         bytesText(free_bytes) + " free: keep fewer logs (--keep-logs first or none) or choose another --log-root";
}

}  // namespace afford
