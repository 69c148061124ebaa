// Planner core: the goal-based planner (paper 2.4.3, Algorithm 2) and the
// utility-based planner (paper 2.4.4, Algorithm 3), one iteration at a time,
// as a state machine that asks for what it needs (a look at the goal image, a
// look at the scene, forward predictions, an action) and is fed the answers.
// No LCM here: the planner node turns requests into messages; tests answer them
// directly from the other cores.
#pragma once
#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "afford/actions.hpp"
#include "afford/config.hpp"
#include "afford/image.hpp"

namespace afford {

// imageDistance of afford/image.hpp, for a predicted image in [0, 1].
double imageDistance(const std::vector<double>& predicted, const std::vector<std::uint8_t>& b);
// ||p - q||_2 for positions in scene units (planner.position_metric: euclidean),
// or half of it (half_euclidean, afford before issue 10).
double positionDistance(double px, double py, double qx, double qy, PositionMetric metric);

struct View {
  std::vector<std::uint8_t> image;  // a focus image
  double x = 0, y = 0;              // where it was taken
};

// Forward-model predictions for one candidate action on the scanned object.
struct ForwardPrediction {
  int action = 0;
  std::vector<double> what;  // predicted focus image after the action
  double where_x = 0, where_y = 0;  // predicted position after the action
};


struct PlannerRequest {
  enum Kind {
    LookAtGoal,     // inner eye: saliency scan of the goal image -> onView
    LookAtSceneAt,  // outer eye: look at (x, y) in the scene -> onView
    ScanScene,      // outer eye: saliency scan of the scene -> onObject (with the object's affordances)
    LookAtDifferences,  // eye (top-down): where goal and scene differ -> onDifferences
    AttendObject,   // outer eye: the object at (x, y) -> onObject (with the object's affordances)
    Forward,        // predictors: what/where effects of `actions` on `image` at (object_x, object_y), imagined
                    // after `prefix`; move target (x, y) -> onForward (with `image`'s affordances if imagined)
    Act,            // environment: execute `action` on the object at (object_x, object_y); move to (x, y) -> onActed
    IterationDone,  // this iteration of Algorithm 2 is over
  } kind = IterationDone;
  double x = -1, y = -1;
  double object_x = -1, object_y = -1;
  std::vector<int> actions;
  int action = -1;
  std::vector<std::uint8_t> image;  // Forward: the object's image, as seen or imagined
  std::vector<int> prefix;          // Forward: the actions imagined before (multi-step search)
};

// What the planner did for one sub-goal (a sub-goal is one pick from the goal image).
struct SubGoalRecord {
  double x = 0, y = 0;
  int iterations = 0;       // 0: the sub-goal was found already reached
  int actions_checked = 0;  // forward predictions compared with the sub-goal
  int actions_taken = 0;
  bool reached = false;
};

// The value of reaching the goal of each object of a scenario, by where the
// goal image shows it (utility planner; paper 2.4.4, Table 8).
struct GoalValue {
  double x = 0, y = 0, value = 0;
};
std::vector<GoalValue> goalValues(const Scenario& s);

// What the core checked and decided, as it does it: `afford explain` replays
// a test's log into the planner node and records these, so an explanation is
// the planner's own account, never a second derivation of it. Every call
// names the iteration (0-based: the `step` of the test's messages). The
// default does nothing; an observer must not throw.
struct PlannerCheck {
  int action = 0;
  double what_distance = 0;   // imageDistance(predicted focus image, sub-goal image)
  bool what_ok = false;       // < planner.image_match
  double where_distance = 0;  // positionDistance(predicted place, sub-goal place, planner.position_metric)
  bool where_ok = false;      // <= planner.position_match
  // Compared: the search stops at the first prediction that passes both, so
  // those after it were predicted but not compared (and not counted).
  bool checked = false;
  bool passes() const { return what_ok && where_ok; }
};
// Why the planner left a sub-goal it had not reached.
enum class SubGoalExit {
  Timeout,        // planner.subgoal_timeout iterations spent on it
  NotActionable,  // top-down attention: no remembered object left to try for it
  Weighed,        // the utility planner weighed an action for it, and acted or not (Algorithm 3)
};
class PlannerObserver {
 public:
  virtual ~PlannerObserver() = default;
  // Every request the core makes, as it makes it (Act: the action decided).
  virtual void requested(int /*iteration*/, const PlannerRequest& /*r*/) {}
  // A sub-goal picked: from the goal image's scan, or a remembered difference (top-down).
  virtual void subGoalPicked(int /*iteration*/, const View& /*sub_goal*/) {}
  // The scene at the sub-goal's place against it: right after the pick, or after an action.
  virtual void reachChecked(int /*iteration*/, bool /*after_action*/, double /*distance*/, bool /*reached*/) {}
  // The object to act on, and what it affords.
  virtual void objectTaken(int /*iteration*/, const View& /*object*/, const std::array<double, kNumActions>& /*affordance*/) {}
  // The forward predictions of one query against the sub-goal, in the answer's
  // order; `prefix`: the actions imagined before (multi-step search), empty for the object itself.
  virtual void predictionsChecked(int /*iteration*/, const std::vector<int>& /*prefix*/,
                                  const std::vector<PlannerCheck>& /*checks*/) {}
  // The sub-goal (its index among those picked) is left unreached.
  virtual void subGoalLeft(int /*iteration*/, std::size_t /*sub_goal*/, SubGoalExit /*why*/) {}
  // An iteration is over; the sub-goals' figures as they stand (what EXTRINSIC_RESULT reports).
  virtual void iterationEnded(int /*iteration*/, const std::vector<SubGoalRecord>& /*sub_goals*/) {}
};

class Planner {
 public:
  // `values`: the sub-goal values of the scenario (used by the utility planner);
  // a sub-goal picked at (x, y) has the value of the nearest goal.
  explicit Planner(const PlannerConfig& config, std::vector<GoalValue> values = {});

  PlannerRequest startIteration();
  // Goals phase (docs/model.md#goals-of-its-own): pursue `goal` (an image at a
  // place) with the object at (object_x, object_y), from a look at the goal
  // place. Each iteration after it attends that object (where the plan under
  // way expects it), plans, and acts on the plan, or on the best guess of the
  // forward models when they find none; an iteration that ends without an
  // action found nothing to try.
  PlannerRequest pursue(const View& goal, double object_x, double object_y);
  PlannerRequest onView(const View& v);
  PlannerRequest onObject(const View& object, const std::array<double, kNumActions>& affordance);
  // `input_affordance`: for an imagined object (a request with a prefix), what it affords.
  PlannerRequest onForward(const std::vector<ForwardPrediction>& predictions,
                           const std::optional<std::array<double, kNumActions>>& input_affordance = std::nullopt);
  PlannerRequest onDifferences(const std::vector<Difference>& differences);
  PlannerRequest onActed();

  int attempts() const { return attempts_; }
  // Utility planner: the current estimate of the attainable utility, and
  // whether the planner is still only estimating it.
  double potentialUtility() const { return potential_utility_; }
  bool evaluating() const { return iterations_ <= config_.evaluation_iterations; }
  double subGoalValue(double x, double y) const;
  bool subGoalActive() const { return active_; }
  // The image distance of the last look at the sub-goal's place (-1: none yet).
  double lastReachDistance() const { return reach_distance_; }
  // The last action came from a plan (not from a best guess).
  bool lastActionPlanned() const { return planned_; }
  const std::vector<SubGoalRecord>& subGoals() const { return records_; }
  // Tell `observer` (not owned; nullptr: none) what the core checks and decides from here on.
  void observe(PlannerObserver* observer) { observer_ = observer; }

 private:
  enum class Wait { Nothing, SubGoal, SceneAtSubGoal, Object, Forward, Acted, SceneAfterAction, Differences };
  // The public on...() and startIteration(), before the observer is told the request.
  PlannerRequest begin();
  PlannerRequest viewed(const View& v);
  PlannerRequest objectSeen(const View& object, const std::array<double, kNumActions>& affordance);
  PlannerRequest predicted(const std::vector<ForwardPrediction>& predictions,
                           const std::optional<std::array<double, kNumActions>>& input_affordance);
  PlannerRequest differencesSeen(const std::vector<Difference>& differences);
  PlannerRequest acted();
  PlannerRequest request(PlannerRequest::Kind kind, double x = -1, double y = -1) const;
  PlannerRequest done();
  PlannerRequest forward(const std::vector<std::uint8_t>& image, double x, double y, std::vector<int> actions,
                         std::vector<int> prefix);

  // Top-down attention: the next sub-goal of the memory, or a new look at the differences.
  PlannerRequest nextTarget();
  // ... the next object to try for it, or leave it as not actionable.
  PlannerRequest attendCandidate();
  // A plan of one action or more was found: act on its first one.
  PlannerRequest actOnPlan(const ForwardPrediction& first, std::size_t length);
  PlannerRequest act(const ForwardPrediction& p);
  // Algorithm 3 once ActionPlanning found `p` for the sub-goal and object.
  PlannerRequest weighUtility(const ForwardPrediction& p);
  // End the iteration on this sub-goal, counted, and pick another next time.
  PlannerRequest leaveSubGoal(SubGoalExit why);
  void left(SubGoalExit why) const;

  // Goals phase: attend the goal's object, where it should be now.
  PlannerRequest attendGoalObject();

  // Every request leaves through here, told to the observer.
  PlannerRequest told(PlannerRequest r) const;
  int iteration() const { return iterations_ - 1; }
  PlannerCheck check(const ForwardPrediction& p) const;

  PlannerConfig config_;
  std::vector<GoalValue> values_;
  PlannerObserver* observer_ = nullptr;
  Wait wait_ = Wait::Nothing;
  int iterations_ = 0;  // started so far
  double potential_utility_ = 0;
  std::array<double, kNumActions> affordance_{};  // of the scanned object
  bool active_ = false;
  int iterations_on_sub_goal_ = 0;
  int attempts_ = 0;
  View sub_goal_, object_;
  std::vector<SubGoalRecord> records_;

  // Multi-step search: breadth first over imagined objects, actions in order.
  struct SearchNode {
    std::vector<int> actions;  // the plan so far
    std::vector<std::uint8_t> image;
    double x = 0, y = 0;
    ForwardPrediction first;   // the prediction for the plan's first action
  };
  std::vector<SearchNode> frontier_;   // nodes still to query, in order (front first)
  std::size_t frontier_next_ = 0;
  SearchNode querying_;                // the node whose query is under way
  int queries_ = 0;                    // forward queries this iteration
  std::optional<View> continue_at_;    // a longer plan's first action was taken: the object is expected here

  // Goals phase: the goal's object, and the best guess of this iteration's
  // first forward query (the prediction nearest the goal, in units of the
  // match thresholds) for when no plan is found.
  bool pursuing_ = false;
  View goal_object_;
  std::optional<ForwardPrediction> best_guess_;
  double best_score_ = 0;
  int last_action_ = -1;
  bool planned_ = false;
  double reach_distance_ = -1;

  // Top-down attention (docs/model.md#top-down-attention): the memory of
  // what the look at the differences showed, and what became of it.
  enum class Status { Pending, Done, NotActionable };
  struct Remembered {
    double x = 0, y = 0;
    std::vector<std::uint8_t> image;
    Status status = Status::Pending;
    std::vector<int> tried;  // targets: the objects tried for it
  };
  bool differences_known_ = false;
  std::vector<Remembered> targets_, objects_;
  int target_ = -1, candidate_ = -1;
};

}  // namespace afford
