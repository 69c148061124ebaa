// Goal choosers of the goals phase (docs/model.md#goals-of-its-own): what a
// goal chooser is, for someone who writes one (docs/writing-a-component.md),
// and the shipped one, `imgep`.
//
// The motivation process's node gives the chooser what the agent saw (each
// object it looked at, each effect of an action with the object as it was
// before), what its forward models imagined for the objects the planner asked
// about, and the outcome of each goal; it asks for the next goal once the
// chooser has been given everything published before the last goal ended, so
// that every choice is a pure function of the run. A chooser holds no protocol
// code; randomness comes from KeyedRng(seed, step, purpose, goal id).
//
// The goals.kind config key picks the chooser: `imgep` ships; a process of
// one's own registers more (registerGoalChooser) before it starts.
#pragma once
#include <array>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "afford/actions.hpp"
#include "afford/config.hpp"
#include "afford/snapshot.hpp"

namespace afford {

// The kinds of change a goal asks for (goal_t's module constants).
enum class GoalModule : int { Explore = 0, Colour = 1, Move = 2, ColourPlace = 3 };
inline constexpr int kGoalModules = 4;
inline constexpr std::array<const char*, kGoalModules> kGoalModuleNames = {"explore", "colour", "move",
                                                                            "colour_place"};

// A focus image and where it was taken.
struct Seen {
  std::vector<std::uint8_t> image;
  double x = 0, y = 0;
};

// An effect the eye saw: the object before (the step's object focus), the
// action, and the object after (the change-driven scan).
struct SeenEffect {
  std::int64_t step = 0;
  int action = 0;
  Seen before, after;
  double target_x = -1, target_y = -1;  // a move's target
  bool affordance = false;              // the action's own effect was seen
};

// What the forward models predict an action does to an object in view.
struct Imagined {
  std::int64_t step = 0;
  int action = 0;
  std::vector<std::uint8_t> object;  // the object's image as seen (the step's object focus)
  std::vector<std::uint8_t> image;  // the predicted focus image, quantised
  double x = 0, y = 0;              // the predicted place
};

// A goal: the image wanted at a place, and the object to act on.
struct Goal {
  GoalModule module = GoalModule::Explore;
  double object_x = -1, object_y = -1;
  double x = -1, y = -1;
  std::vector<std::uint8_t> image;
  int action = -1;  // Explore: the action to try
};

// What became of a goal.
struct GoalAttempt {
  int id = 0;
  GoalModule module = GoalModule::Explore;
  bool reached = false;
  double distance = -1;
  int actions = 0;
};

// How far an object reaches from its centre, and how close two objects' centres can stand, in scene units:
// the grid's shapes by world.object_size (a rectangle reaches 0.75 sizes; every shape holds a disc of a third of
// the size), the table's objects by their sizes as the camera sees their tops (any of them may lie: its longest
// half-extent; two touch: their narrowest half-widths). Computed from the run's configuration.
struct ObjectGeometry {
  double reach = 0;
  double apart = 0;
};
ObjectGeometry objectGeometry(const RunConfig& c);

// What a chooser is given of the run's configuration.
struct GoalParams {
  GoalsConfig goals;
  PlannerConfig planner;
  WorldConfig world;
  ObjectGeometry geometry;
  int focus_side = 0;
  std::int64_t seed = 0;
  std::int64_t steps = 0;
  std::string experiment;
  System system = System::GOALS;
  std::string config_text;  // the run's configuration, YAML (for a chooser that reads it whole)
  GoalParams() = default;
  GoalParams(const RunConfig& c)  // NOLINT: the sections a run's configuration gives
      : goals(c.goals), planner(c.planner), world(c.world), geometry(objectGeometry(c)), focus_side(c.eye.focus_side), seed(c.seed),
        steps(c.steps), experiment(c.experiment), system(c.system), config_text(c.text) {}
};

class GoalChooser {
 public:
  virtual ~GoalChooser() = default;
  virtual void sawObject(std::int64_t /*step*/, const Seen& /*object*/) {}
  virtual void sawEffect(const SeenEffect& /*effect*/) {}
  virtual void imagined(const Imagined& /*outcome*/) {}
  virtual void attempted(const GoalAttempt& /*attempt*/) {}
  // Goal number `id`, whose pursuit begins at `step`.
  virtual Goal next(std::int64_t step, int id) = 0;
  // Snapshots, as for a motivation (motivation/component.hpp).
  virtual bool snapshots() const { return false; }
  virtual void save(SnapshotWriter&) const {}
  virtual void load(SnapshotReader&) {}
};

// An exploration: goal number `id` (set at `step`) tries an action drawn by its key (seed, step,
// Purpose::GoalChoice, id), whatever the object in view. A chooser's way to start, and the motivation's
// when goals are found reached one after another without a step taken.
Goal explorationGoal(std::int64_t seed, std::int64_t step, int id);

using GoalChooserFactory = std::function<std::unique_ptr<GoalChooser>(const GoalParams&)>;
void registerGoalChooser(const std::string& kind, GoalChooserFactory factory);
std::vector<std::string> goalChooserKinds();
// The chooser goals.kind names; throws ConfigError naming the key and the kinds known.
std::unique_ptr<GoalChooser> makeGoalChooser(const GoalParams& params);

// Each module's recent competence: its last 2 x window attempts (1 reached, 0
// not). Its progress is |mean of the newer half - mean of the older half|, the
// absolute competence progress of IMGEP and CURIOUS.
class Competence {
 public:
  explicit Competence(int window) : window_(window) {}
  void attempted(GoalModule m, double competence);
  double progress(GoalModule m) const;
  std::size_t attempts(GoalModule m) const { return history_[static_cast<std::size_t>(m)].size(); }
  // A module among those `available`: uniformly with probability random_share
  // (or when no module shows progress), else in proportion to progress.
  // `u` and `v`: two uniform draws in [0, 1).
  GoalModule choose(const std::array<bool, kGoalModules>& available, double random_share, double u, double v) const;
  void save(SnapshotWriter& w) const;
  void load(SnapshotReader& r);

 private:
  int window_;
  std::array<std::deque<double>, kGoalModules> history_;
};

// The shipped chooser (goals.kind: imgep): goals from the outcomes the agent
// saw and imagined, on the objects it last saw, a module chosen by competence
// progress.
class ImgepChooser : public GoalChooser {
 public:
  explicit ImgepChooser(const GoalParams& params);
  void sawObject(std::int64_t step, const Seen& object) override;
  void sawEffect(const SeenEffect& effect) override;
  void imagined(const Imagined& outcome) override;
  void attempted(const GoalAttempt& attempt) override;
  Goal next(std::int64_t step, int id) override;
  bool snapshots() const override { return true; }
  void save(SnapshotWriter& w) const override;
  void load(SnapshotReader& r) override;

  const Competence& competence() const { return competence_; }
  std::size_t objects() const { return objects_.size(); }
  std::size_t colours() const { return colours_.size(); }
  std::size_t places() const { return places_.size(); }

 private:
  // The table world's effects (world.kind: table): push and carry take an object to a place; a topple (or a
  // roll that turned it) leaves it in a new look where the change-driven scan found it.
  void sawTableEffect(const SeenEffect& e);
  void rememberPlace(double x, double y);
  void rememberLook(Seen look);  // a colour outcome (a look), unless one as near is known
  // A look (a colour outcome) that fits an object (on the table, one of its colour: next() checks the colours),
  // and the place it would be seen at.
  bool fits(const Seen& object, const Seen& look) const;
  Seen lookPlace(const Seen& object, const Seen& look) const;
  // The object seen last near (x, y), if any.
  std::deque<Seen>::iterator objectAt(double x, double y);
  void remember(std::deque<Seen>& where, Seen s);
  bool samePlace(double ax, double ay, double bx, double by) const;
  // No object the chooser knows of stands near (x, y) but `except`.
  bool freeAt(double x, double y, const Seen* except) const;

  GoalParams params_;
  bool table_;  // the physical table's objects and actions (world.kind: table)
  // Centres at least this far apart on either axis: an object's focus window does not show the other, and a move
  // there is carried out (the environment moves an object only to a place whose window is free).
  double clear_;
  Competence competence_;
  std::deque<Seen> objects_;  // the objects as last seen (one per place)
  // Colour outcomes: images objects took after a colour change (seen or imagined); on the table, looks objects
  // took where they stood (seen), each with the change of its centre as its x, y.
  std::deque<Seen> colours_;
  std::deque<Seen> places_;   // places objects were moved to, or left
  double last_x_ = -1, last_y_ = -1;  // the place of the last goal set
};

}  // namespace afford
