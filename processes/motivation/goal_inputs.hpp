// What the goal chooser is to be given (motivation/goals.hpp), held until the
// GOAL_RESULT it came before in the run. The motivation takes FOCUS, EFFECT and
// FORWARD_PREDICTION as they come; a process catching up from a snapshot gets
// them ahead of the results they came before. Given to the chooser at each
// goal's end, those before it only, in the run's order (by step; an object
// and the predictions about it by the planner's request seq; a step's effect
// after them), the chooser's state is a function of the run whatever the
// order of arrival.
#pragma once
#include <array>
#include <cstdint>
#include <map>
#include <vector>

#include "afford/snapshot.hpp"
#include "motivation/goals.hpp"

namespace afford {

class GoalInputs {
 public:
  // What is held: an object look, what the forward models imagined of it, an effect.
  enum Kind : int { Object = 0, Forward = 1, Effect = 2 };
  static constexpr int kKinds = 3;
  // An object FOCUS of `step`, answering request `seq`.
  void object(std::int64_t step, std::int32_t seq, Seen seen);
  // The EFFECT of the action of `step` (its object before is the step's object FOCUS).
  void effect(SeenEffect effect);
  // What the forward models predict for the object of `step` (each Imagined's object is that FOCUS's image).
  void forward(std::int64_t step, std::int32_t seq, std::vector<Imagined> outcomes);
  // Everything before the end of a goal whose GOAL_RESULT has `step` and `seq`, to the chooser, in order.
  void feed(GoalChooser& chooser, std::int64_t step, std::int32_t seq);
  std::size_t held() const { return pending_.size(); }
  // Held of one kind. A node caps each kind apart: one channel far ahead (a process catching up) must not take
  // the room another needs before the next goal can end.
  std::size_t held(Kind k) const { return held_[static_cast<std::size_t>(k)]; }
  void clear();
  void save(SnapshotWriter& w) const;
  void load(SnapshotReader& r, std::int64_t steps, std::size_t image_bytes, std::size_t most);

 private:
  struct Entry {
    std::int64_t step = 0;
    Kind kind = Object;
    std::int32_t seq = 0;
    Seen seen;                   // Object
    SeenEffect effect;           // Effect
    std::vector<Imagined> imagined;  // Forward
  };
  void add(Entry e);
  std::vector<Entry> pending_;
  std::array<std::size_t, kKinds> held_{};  // pending_ by kind
  std::map<std::int64_t, Seen> objects_;  // each step's object as given, for the effects and predictions of that step
};

}  // namespace afford
