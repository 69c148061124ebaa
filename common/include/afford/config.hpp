// Typed run configuration (docs/configuration.md): loaded once from YAML, validated
// strictly. Every error names the offending key, e.g.
//   config key 'predictors.affordance.learning_rate': expected a number, got "fast"
// The effective configuration of a run travels as YAML text in run_config_t,
// so every process parses it with this same code.
#pragma once
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "afford/actions.hpp"
#include "afford/phase.hpp"
#include "afford/table_world.hpp"

namespace afford {

class ConfigError : public std::runtime_error {
 public:
  explicit ConfigError(const std::string& what, std::string key = {}) : std::runtime_error(what), key_(std::move(key)) {}
  // The config key the error is about ("motivation.leak"), when it is about one.
  const std::string& key() const { return key_; }

 private:
  std::string key_;
};

enum class Shape { Square, Circle, Rectangle };
enum class Colour { Red, Green, Blue };
// The paper's three systems (paper 2.4.1), and GOALS: the agent that sets its
// own goals (the goals phase, docs/model.md#goals-of-its-own).
enum class System { FIX, IGN, IMP, GOALS };
enum class SaliencyOrder { SmoothThenNoise, NoiseThenSmooth };
enum class ImpThresholdInput { Signal, ObservedChange };
// How object centres become pixels (world.positions, docs/parameters.md).
// Which world the environment simulates: the paper's (a 2D scene of flat shapes and an affordance table the
// configuration gives) or a physical table (MuJoCo, a camera, a hand: affordances physics decides).
enum class WorldKind { Grid, Table };
// Whether an action is given a place (a move target): the grid's move; the table's push and carry.
inline bool takesPlace(WorldKind k, int action) { return k == WorldKind::Table ? action == 0 || action == 1 : action == kMove; }
// An action's name in a world (kActionNames, kTableActionNames).
inline std::string_view actionName(WorldKind k, int action) {
  return validAction(action) ? (k == WorldKind::Table ? kTableActionNames : kActionNames)[static_cast<std::size_t>(action)]
                             : std::string_view("none");
}

enum class Positions {
  Continuous,  // real-valued centres and move targets, each shape rasterised from its centre (authors' code)
  Pixel,       // centres snapped to a pixel, one fixed footprint per shape (afford before issue 10)
};

const char* toString(Shape);
const char* toString(Colour);
const char* toString(System);
System parseSystem(const std::string&);  // throws ConfigError
int colourChannel(Colour);                // R=0, G=1, B=2

struct ObjectSpec {
  std::string name;                        // "red square"
  Shape shape = Shape::Square;
  Colour colour = Colour::Red;
  double x = 0.5, y = 0.5;                 // start position, scene units
  std::int64_t appears_at = 0;             // step at which the object enters the scene
  std::array<double, kNumActions> affordance{};  // success probability per action
};

// Every value below comes from the effective configuration (config/*.yaml,
// where each paper value is written down with its source); the initialisers
// are neutral placeholders, never used: parseRunConfig requires every key.
struct WorldConfig {
  WorldKind kind = WorldKind::Grid;
  int size_px = 0;                       // scene width in pixels (side = 1 unit; table world: the camera's width)
  int height_px = 0;                     // scene height in pixels (grid: size_px; table world: the camera's)
  // Steps at which the scene is set up anew (table world: table.scene.reset_every; 0: never).
  std::int64_t reset_every = 0;
  double object_size = 0;               // square side / reference size, scene units
  double table_min = 0, table_max = 0; // allowed object centres
  int max_target_draws = 0;             // intrinsic move: redraws for a free target
  Positions positions = Positions::Continuous;
  // Continuous positions: a late object's place is free of the objects present
  // before its step only, so late objects of one step may overlap (authors' code).
  bool late_overlap = true;
  std::vector<ObjectSpec> objects;         // in the order of the paper's tables

  // The scene's rows (a configuration built in code may leave height_px 0: a square scene).
  int rows() const { return height_px > 0 ? height_px : size_px; }

  // Whether the world changes the scene at `step`: late objects enter it (those present from the start have
  // appears_at 0), or the table world sets it up anew.
  bool lateObjectsAt(std::int64_t step) const {
    if (reset_every > 0) return step > 0 && step % reset_every == 0;
    return step > 0 && std::any_of(objects.begin(), objects.end(), [&](const ObjectSpec& o) { return o.appears_at == step; });
  }
};

// How the extrinsic phase finds sub-goals and objects (issue 12): the paper's
// bottom-up saliency scans, or a top-down look at where scene and goal differ,
// remembered by the planner.
enum class Attention { BottomUp, TopDown };
// Where the eye puts its window on an object it found (issue 28): on the blob's
// centroid, from the image alone (ours); or on the object's true centre, which
// the environment then lists in each SCENE (the authors' eye).
enum class Fovea { BlobCentroid, TrueCentre };

struct EyeConfig {
  int focus_side = 0;                     // pixels
  double saliency_noise = 0;            // uniform noise half-width
  double saliency_sigma_px = 0;          // Gaussian smoothing of the saliency image
  SaliencyOrder saliency_order = SaliencyOrder::SmoothThenNoise;
  double change_sigma_px = 0;            // Gaussian smoothing of the change image
  double initial_gaze_x = 0, initial_gaze_y = 0;
  double image_change_threshold = 0;    // tau_i
  double position_change_threshold = 0; // tau_p
  int max_scan_draws = 0;                // redraws until the gaze lands on another object
  Attention attention = Attention::BottomUp;  // extrinsic phase (issue 12)
  Fovea fovea = Fovea::BlobCentroid;
};

// The agent's memory of past experiences (issue 11, docs/model.md#memory):
// kept when replay or revisits need it; the paper's agent has none.
// Do the predictors keep a memory (docs/model.md#memory)? auto: when replay,
// revisits or a motivation other than the paper's may use it.
enum class MemoryKeep { Auto, Always, Never };
struct MemoryConfig {
  double look_threshold = 0;    // two focus images show one look below this distance (L1 per value, 0..1)
  int look_shift_px = 0;        // ... allowing the images to be shifted by up to this many pixels
  int max_looks = 0;            // looks remembered; a new one replaces the one seen least recently
  int per_look_action = 0;      // experiences kept per look and action (the newest)
  MemoryKeep keep = MemoryKeep::Auto;
};
enum class ReplaySampling {
  Balanced,  // a remembered (look, action) uniformly, then one of its experiences
  Uniform,   // any remembered experience
};
struct ReplayConfig {
  bool enabled = false;   // off: no replay, the paper's agent
  int ratio = 0;          // replayed affordance updates per intrinsic step
  double effects_ratio = 0;  // forward-model updates per intrinsic step, on average: the step's own, remembered ones for the rest
  ReplaySampling sampling = ReplaySampling::Balanced;
};

struct PredictorsConfig {
  // The affordance component (predictors/affordance.hpp): the affordance and
  // learning-progress predictors; paper, or one a process registers.
  std::string affordance_kind = "paper";
  double affordance_learning_rate = 0;
  double learning_progress_learning_rate = 0;
  double learning_progress_init = 0;  // magnitude of the random-sign initial weights
  double what_effect_learning_rate = 0;
  double where_effect_learning_rate = 0;
  MemoryConfig memory;
  ReplayConfig replay;
};

// Revisits (issue 11, docs/model.md#revisit): whatever the IM signal says,
// try on the focused look an action never tried on it, or not tried for
// after_steps steps. Off in the paper's agent.
enum class RevisitOrder {
  Actions,  // never-tried actions in the action order: move, turn green, turn red, turn blue
  Random,   // move first (it keeps the look), then the never-tried colours in an order drawn per step
};
struct RevisitConfig {
  bool enabled = false;
  std::int64_t after_steps = 0;  // 0: only actions never tried on the look
  RevisitOrder order = RevisitOrder::Actions;
};

struct MotivationConfig {
  std::string kind = "paper";            // the motivation component (motivation/component.hpp): paper, novelty, ...
  double novelty_threshold = 0;          // novelty: act while 1 / sqrt(1 + n) is at least this
  double fixed_threshold = 0;            // FIX
  double leak = 0;                       // nu of equation 2 (IGN, IMP)
  double initial_threshold = 0;          // th_0 (IGN, IMP)
  double act_margin = 0;                // act when motivation + margin >= threshold
  ImpThresholdInput imp_threshold_input = ImpThresholdInput::Signal;
  RevisitConfig revisit;
};

// The goals phase (docs/model.md#goals-of-its-own): how the agent sets,
// chooses and pursues its own goals.
struct GoalsConfig {
  std::string kind = "imgep";  // the goal chooser (motivation/goals.hpp): imgep, or one a process registers
  int budget = 0;              // actions the planner may spend on one goal
  int window = 0;              // attempts per module in each half of its competence window
  double random_share = 0;     // share of module choices drawn uniformly, the rest by |competence progress|
  double explore_share = 0;    // share of goals that try a random action on a scanned object (motor babbling)
  int bootstrap = 0;           // goals at the start of a run that are explorations
  int memory = 0;              // outcomes, places and objects the chooser keeps (the oldest go first)
  int held = 0;                // inputs of each kind the motivation holds ahead of the goal results they come before
};

// An extrinsic-phase scenario (paper 3.1, Figure 4): objects with the state
// they start in and the state the goal image shows.
struct ObjectState {
  Colour colour = Colour::Red;
  double x = 0, y = 0;
};
struct ScenarioObject {
  Shape shape = Shape::Square;
  ObjectState initial, goal;
  double value = 0;  // utility of reaching this object's goal (utility planner)
  int actions = 1;   // actions its goal needs: 1, or 2 and more for a goal that changes colour and place (issue 12)
  // The table world: which of table.objects (its name, and its index there); shape and colour are the grid's.
  std::string object;
  int object_index = -1;
};
struct Scenario {
  std::string name;
  std::string description;
  WorldKind world = WorldKind::Grid;  // the world it is of (`world:` in its file; the grid if not given)
  std::vector<ScenarioObject> objects;
};

enum class PlannerKind { Goal, Utility };
// The distance of a predicted where-effect from the sub-goal's place.
enum class PositionMetric { Euclidean, HalfEuclidean };

struct PlannerConfig {
  double subgoal_match = 0;         // sub-goal reached: image distance below this (paper 2.4.3)
  double image_match = 0;         // predicted image matches the sub-goal (paper 2.4.3)
  double position_match = 0;        // predicted position matches the sub-goal (paper 2.4.3)
  PositionMetric position_metric = PositionMetric::Euclidean;  // how that distance is measured
  int subgoal_timeout = 0;             // iterations before another sub-goal is chosen (paper 2.4.3)
  int budget = 0;                    // steps per test (authors' code)
  int max_attempts = 0;               // executed actions per test (authors' code)
  bool restrict_by_affordance = false;  // check only actions with affordance > affordance_threshold
  double affordance_threshold = 0;   // (paper 2.4.3, 3.2.4)
  double success_distance = 0;      // whole scene matches the goal image (authors' code)
  PlannerKind kind = PlannerKind::Goal;  // Algorithm 2 or Algorithm 3
  Attention attention = Attention::BottomUp;  // eye.attention: the eye and the planner read one key
  WorldKind world = WorldKind::Grid;          // world.kind: which actions are given a place (takesPlace)
  // Multi-step search (issue 12): plans of up to max_depth actions through the
  // forward models, at most max_queries forward queries per iteration.
  int max_depth = 1;                 // 1: the paper's one-step planner
  int max_queries = 0;
  // Utility-based planner (paper 2.4.4, Algorithm 3).
  int evaluation_iterations = 0;     // iterations that only estimate the potential utility
  double raise_leak = 0;             // nu of the leaky average raising the potential utility
  double lower_leak = 0;             // nu of the leaky average lowering it (towards 0) per chosen action
};

// The names of an enum's values as the configuration spells them, declared
// once: the parser reads them, nameOf (and toString) print them.
template <class E>
struct Named {
  const char* name;
  E value;
};
inline constexpr std::array<Named<Shape>, 3> kShapeNames{
    {{"square", Shape::Square}, {"circle", Shape::Circle}, {"rectangle", Shape::Rectangle}}};
inline constexpr std::array<Named<Colour>, 3> kColourNames{
    {{"red", Colour::Red}, {"green", Colour::Green}, {"blue", Colour::Blue}}};
inline constexpr std::array<Named<System>, 4> kSystemNames{
    {{"FIX", System::FIX}, {"IGN", System::IGN}, {"IMP", System::IMP}, {"GOALS", System::GOALS}}};
inline constexpr std::array<Named<Phase>, kPhases> kPhaseNames{
    {{"intrinsic", Phase::Intrinsic}, {"extrinsic", Phase::Extrinsic}, {"goals", Phase::Goals}}};
inline constexpr std::array<Named<WorldKind>, 2> kWorldKindNames{{{"grid", WorldKind::Grid}, {"table", WorldKind::Table}}};
inline constexpr std::array<Named<table::Shape>, 3> kTableShapeNames{
    {{"box", table::Shape::Box}, {"cylinder", table::Shape::Cylinder}, {"sphere", table::Shape::Sphere}}};
inline constexpr std::array<Named<Positions>, 2> kPositionsNames{
    {{"continuous", Positions::Continuous}, {"pixel", Positions::Pixel}}};
inline constexpr std::array<Named<SaliencyOrder>, 2> kSaliencyOrderNames{
    {{"smooth_then_noise", SaliencyOrder::SmoothThenNoise}, {"noise_then_smooth", SaliencyOrder::NoiseThenSmooth}}};
inline constexpr std::array<Named<Attention>, 2> kAttentionNames{
    {{"bottom_up", Attention::BottomUp}, {"top_down", Attention::TopDown}}};
inline constexpr std::array<Named<Fovea>, 2> kFoveaNames{
    {{"blob_centroid", Fovea::BlobCentroid}, {"true_centre", Fovea::TrueCentre}}};
inline constexpr std::array<Named<MemoryKeep>, 3> kMemoryKeepNames{
    {{"auto", MemoryKeep::Auto}, {"always", MemoryKeep::Always}, {"never", MemoryKeep::Never}}};
inline constexpr std::array<Named<ReplaySampling>, 2> kReplaySamplingNames{
    {{"balanced", ReplaySampling::Balanced}, {"uniform", ReplaySampling::Uniform}}};
inline constexpr std::array<Named<ImpThresholdInput>, 2> kImpThresholdInputNames{
    {{"signal", ImpThresholdInput::Signal}, {"observed_change", ImpThresholdInput::ObservedChange}}};
inline constexpr std::array<Named<RevisitOrder>, 2> kRevisitOrderNames{
    {{"actions", RevisitOrder::Actions}, {"random", RevisitOrder::Random}}};
inline constexpr std::array<Named<PlannerKind>, 2> kPlannerKindNames{
    {{"goal", PlannerKind::Goal}, {"utility", PlannerKind::Utility}}};
inline constexpr std::array<Named<PositionMetric>, 2> kPositionMetricNames{
    {{"euclidean", PositionMetric::Euclidean}, {"half_euclidean", PositionMetric::HalfEuclidean}}};
inline constexpr std::array<Named<bool>, 2> kBoolNames{{{"true", true}, {"false", false}}};

template <class E, std::size_t N>
const char* nameOf(const std::array<Named<E>, N>& names, E value) {
  for (const auto& n : names)
    if (n.value == value) return n.name;
  return "?";
}

// The message edge (config key `protocol`, docs/processes-and-channels.md):
// how fast a lost datagram is found and asked for again, how long the runner
// and the logger wait for the others, and what a receiver accepts. None of it
// changes what a run computes. A process uses the values of its run's
// configuration, and those of the config folder's defaults.yaml between runs.
struct ProtocolLimits {       // what a receiver accepts before a run's configuration says more
  int name_bytes = 0;         // run ids, process, channel, experiment and object names
  int text_bytes = 0;         // STATUS detail
  int config_bytes = 0;       // RUN_CONFIG config_yaml
  int objects = 0;            // objects of a probe or an affordance table
  int focus_side = 0;         // side of a focus image, pixels
  int scene_side = 0;         // side of a scene, pixels
  int sub_goals = 0;          // sub-goal records of an extrinsic result
  int run_id_bytes = 0;       // a run id (it names folders and files: afford/names.hpp)
  int peers = 0;              // processes (name, pid) a listener keeps track of (afford status, the edge)
  int control_messages = 0;   // distinct RUN_CONFIG and RUN_CONTROL messages the logger records in one run
};
// LCM's receive path (third_party/lcm), set on a process's udpm URL when it
// opens the bus: from its config folder's defaults.yaml, not a run's.
struct BusConfig {
  int max_message_bytes = 0;    // a larger message is dropped by LCM (and refused by a publisher)
  int fragment_bytes = 0;       // incomplete fragmented messages hold at most this together
  int fragment_timeout_ms = 0;  // an incomplete fragmented message is dropped this long after its first fragment
  int queue_bytes = 0;          // received messages waiting to be handled hold at most this together
};
// Runs of any length (docs/processes-and-channels.md#runs-of-any-length): what a process holds for a restart.
struct RecoveryConfig {
  int snapshot_steps = 0;  // a process saves its state every this many steps (0: never; older logs)
  int history_keep = 0;    // messages of each channel a publisher holds whatever its readers' snapshots say
  int history_mb = 0;      // what a process holds of what it published, at most (0: no bound; older logs)
  int snapshot_mb = 0;     // the largest snapshot a restarted process reads
};
struct ProtocolConfig {
  int heartbeat_ms = 0;       // STATUS period
  int idle_announce_ms = 0;   // a process of a run idle this long announces its counts at once
  int idle_announce_pace = 0; // ... and idle this many times its usual wait for an input (0: absent, older logs)
  int freshness_ms = 0;       // keyed bus: a sender not heard yet is taken only if its message is this recent (0: any)
  int retry_ms = 0;           // an unanswered RESEND is asked again after this (then doubling up to heartbeat_ms)
  int resend_batch = 0;       // serials asked for in one RESEND
  int resend_cap = 0;         // serials a publisher republishes for one RESEND
  int resend_budget = 0;      // serials a publisher republishes per channel within retry_ms
  int stop_grace_ms = 0;      // after STOP, the logger waits this long for missing messages
  int ready_timeout_ms = 0;   // the runner fails a run whose processes are not free, configured or started by then
  int close_timeout_ms = 0;   // the runner fails a run whose log is not closed this long after STOP
  int max_deferred = 0;       // messages waiting for their turn in a process; reaching it fails the run
  int queue_capacity = 0;     // LCM's queue of each subscription, messages
  ProtocolLimits limits;
  BusConfig bus;
  RecoveryConfig recovery;
};

struct RunConfig {
  std::string experiment;
  Phase phase = Phase::Intrinsic;
  // Extrinsic phase: the trained predictors to load, and the scenario of the test.
  std::string extrinsic_checkpoint;
  std::optional<Scenario> scenario;
  System system = System::IMP;
  std::int64_t seed = 0;
  std::int64_t steps = 0;
  std::int64_t curve_interval = 0;
  std::string checkpoint;  // where the predictors save their weights after the last step ("" = nowhere)
  // Also save the weights as they are after this many executed actions (0 = not), to
  // actionsCheckpoint(checkpoint, n): paper 3.2.3 tests agents trained for 4000 actions.
  std::int64_t checkpoint_after_actions = 0;
  bool record = true;  // a logger on the bus records this run (afford experiment --keep-logs decides)
  WorldConfig world;
  table::TableWorldConfig table;  // world.kind: table (the `table` section)
  EyeConfig eye;
  PredictorsConfig predictors;
  MotivationConfig motivation;
  GoalsConfig goals;
  PlannerConfig planner;
  ProtocolConfig protocol;

  // The predictors keep a memory of experiences: replay, revisits and every
  // motivation but the paper's use it (its looks, what was tried on them).
  // predictors.memory.keep decides; auto keeps it for any of those.
  bool keepsMemory() const {
    if (predictors.memory.keep != MemoryKeep::Auto) return predictors.memory.keep == MemoryKeep::Always;
    return predictors.replay.enabled || motivation.revisit.enabled || motivation.kind != "paper";
  }
  // The YAML text this configuration was parsed from (parseRunConfigText; the
  // run's RUN_CONFIG), for a component that reads it whole (afford's Python
  // components get it as a dict).
  std::string text;
};

// Parse a scenario (types, names, ranges); `path` prefixes the keys in errors.
// Geometry (overlaps, reachability) is checked by validateScenario().
Scenario parseScenario(const YAML::Node& node, const std::string& path, const WorldConfig& world);
// Geometry: objects may not overlap (initial or goal), and each object's goal
// must be one action away: the same state, a colour change in place, or a move
// to a place no other object starts or ends in. Throws ConfigError naming the field.
void validateScenario(const Scenario& s, const WorldConfig& world);
// The same for a run's world, the table's included: there each object's places must lie in the table's region
// (table.truth.region, seen through the camera) and the objects' footprints apart by table.scene.gap, in the
// initial scene and in the goal's.
void validateScenario(const Scenario& s, const RunConfig& run);

// The file of a checkpoint taken after `actions` executed actions, beside `checkpoint`.
std::string actionsCheckpoint(const std::string& checkpoint, std::int64_t actions);

// Every key of a run's configuration, as declared once (common/src/config_keys.hpp).
struct KeyInfo {
  enum class Origin {
    Defaults,    // config/defaults.yaml gives it (with its source), experiment files and --set change it
    Runner,      // the runner sets it for each run (the experiment, system, seed; an extrinsic test's checkpoint)
    Experiment,  // each experiment file gives it (world.objects)
  };
  std::string key;      // "motivation.leak"
  std::string type;     // "number in [0, 1]", "one of goal, utility", ...
  std::string meaning;  // one line
  Origin origin = Origin::Defaults;
};
std::vector<KeyInfo> configKeys();

// A YAML tree as text, numbers with every digit they need.
std::string emitYaml(const YAML::Node& node);

// Parse and validate an effective configuration. Unknown keys are errors too.
RunConfig parseRunConfig(const YAML::Node& root);
RunConfig parseRunConfigText(const std::string& yaml_text);
// The `protocol` section alone (keys named from `path`).
ProtocolConfig parseProtocol(const YAML::Node& node, const std::string& path = "protocol");
// The protocol of config_dir/defaults.yaml: what a process uses between runs.
ProtocolConfig loadProtocol(const std::string& config_dir);

}  // namespace afford
