// Algorithms 1 and 2 written as plain loops over the process cores, with no
// messages. The choreography of processes must compute exactly what these
// compute; they also let tests try the planner quickly.
#pragma once
#include <cmath>

#include "afford/image.hpp"
#include "environment/environment.hpp"
#include "eye/eye.hpp"
#include "motivation/motivation.hpp"
#include "planner/planner.hpp"
#include "predictors/predictors.hpp"

namespace afford::test {

// Algorithm 1 for config.steps steps; returns the trained predictors. With
// predictors.replay or motivation.revisit, the memory's part too (see(),
// tried_ago, replay).
inline Predictors runIntrinsic(const RunConfig& c) {
  Environment env(c);
  Eye eye(c);
  Predictors predictors(c);
  Motivation motivation(c);
  eye.setScene(env.render(), env.centres());
  for (std::int64_t t = 0; t < c.steps; ++t) {
    const Focus f = eye.scan(t);
    const Prediction p = predictors.see(f.image, t);
    const Decision d = motivation.decide(p.affordance, p.learning_progress, p.remembered ? &p.tried_ago : nullptr, t);
    const bool more = t + 1 < c.steps;
    if (d.act) {
      const ActionOutcome out = env.execute(t, d.action, f.x, f.y);
      const Effect e = eye.scanEffect(t, env.render(), d.action, env.centres());
      Experience x;
      x.action = d.action;
      x.before_image = f.image;
      x.before_x = f.x;
      x.before_y = f.y;
      x.target_x = out.target_x;
      x.target_y = out.target_y;
      x.affordance = e.affordance;
      x.after_image = e.after.image;
      x.after_x = e.after.x;
      x.after_y = e.after.y;
      const TrainingReport r = predictors.train(x, t, p.look);
      if (motivation.awaitingObservation()) motivation.observeChange(std::abs(r.affordance_after - r.affordance_before));
    } else {
      predictors.trainEffects(predictors.replay(t));  // a pass: the step's replay alone
    }
    if (more && env.introduceObjectsAt(t + 1)) eye.setScene(env.render(), env.centres());
  }
  return predictors;
}

struct GoalTestOutcome {
  bool success = false;
  int completion = 0;  // the step (from 1) at which the scene matched the goal
  int attempts = 0;
  double utility = 0;  // value of the objects in their goal state at the end
  std::vector<SubGoalRecord> sub_goals;
};

// One extrinsic test of Algorithm 2 (or 3, by c.planner.kind) on a scenario.
inline GoalTestOutcome runGoalTest(const RunConfig& c, const Scenario& s, const Predictors& predictors) {
  Environment env(c, s);
  Eye eye(c);
  eye.setGoal(env.goalScene(), env.goalCentres());
  eye.setScene(env.render(), env.centres());
  Planner planner(c.planner, goalValues(s));
  GoalTestOutcome out;
  auto asView = [](const Focus& f) { return View{f.image, f.x, f.y}; };
  for (int step = 0; step < c.planner.budget && planner.attempts() < c.planner.max_attempts; ++step) {
    PlannerRequest r = planner.startIteration();
    while (r.kind != PlannerRequest::IterationDone) {
      switch (r.kind) {
        case PlannerRequest::LookAtGoal:
          r = planner.onView(asView(eye.scanGoal(step)));
          break;
        case PlannerRequest::LookAtSceneAt:
          r = planner.onView(asView(eye.lookAt(r.x, r.y)));
          break;
        case PlannerRequest::ScanScene:
        case PlannerRequest::AttendObject: {
          const View object = asView(r.kind == PlannerRequest::ScanScene ? eye.scan(step) : eye.attend(r.x, r.y));
          r = planner.onObject(object, predictors.predict(object.image).affordance);
          break;
        }
        case PlannerRequest::LookAtDifferences: {
          r = planner.onDifferences(eye.goalDifferences(c.planner.subgoal_match));
          break;
        }
        case PlannerRequest::Forward: {
          std::vector<ForwardPrediction> preds;
          for (int a : r.actions) {
            const auto where = predictors.whereEffect(a, r.object_x, r.object_y, r.x, r.y);
            // (the what-effect travels as float32 in FORWARD_PREDICTION)
            std::vector<double> what;
            for (double v : predictors.whatEffect(a, r.image)) what.push_back(static_cast<float>(v));
            preds.push_back({a, what, where[0], where[1]});
          }
          std::optional<std::array<double, kNumActions>> input;
          if (!r.prefix.empty()) input = predictors.predict(r.image).affordance;
          r = planner.onForward(preds, input);
          break;
        }
        case PlannerRequest::Act: {
          std::optional<std::pair<double, double>> target;
          if (r.action == kMove) target = std::make_pair(r.x, r.y);
          env.execute(step, r.action, r.object_x, r.object_y, target);
          eye.setScene(env.render(), env.centres());
          r = planner.onActed();
          break;
        }
        case PlannerRequest::IterationDone:
          break;
      }
    }
    if (env.goalDistance() < c.planner.success_distance) {
      out.success = true;
      out.completion = step + 1;
      break;
    }
  }
  out.attempts = planner.attempts();
  out.utility = env.goalUtility();
  out.sub_goals = planner.subGoals();
  return out;
}

}  // namespace afford::test
