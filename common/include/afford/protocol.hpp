// The protocol of a run, in one place: every channel with its message type,
// who publishes it in each phase, who reads it, whether the log records it,
// and when it goes out. Everything that names channels derives from it: the
// edge's subscriptions and publications (typed: a channel is subscribed and
// published only with its own type, or the code does not compile), the
// registry of processes (afford/processes.hpp: what each one publishes), the
// logger's recording list, the runner, the viewer, replay, explain,
// `afford processes --channels`, and the channel table of
// docs/processes-and-channels.md (`afford processes --protocol` prints it; a
// test compares them).
#pragma once
#include <array>
#include <cstring>
#include <string>
#include <tuple>
#include <vector>

#include "afford/affordance_table_t.hpp"
#include "afford/decision_t.hpp"
#include "afford/effect_t.hpp"
#include "afford/extrinsic_result_t.hpp"
#include "afford/focus_t.hpp"
#include "afford/forward_prediction_t.hpp"
#include "afford/forward_query_t.hpp"
#include "afford/goal_result_t.hpp"
#include "afford/goal_t.hpp"
#include "afford/look_t.hpp"
#include "afford/object_probe_t.hpp"
#include "afford/prediction_t.hpp"
#include "afford/process_status_t.hpp"
#include "afford/resend_t.hpp"
#include "afford/run_config_t.hpp"
#include "afford/run_control_t.hpp"
#include "afford/run_result_t.hpp"
#include "afford/scene_t.hpp"
#include "afford/wire_bounds.hpp"
#include "afford/phase.hpp"

namespace afford {

// Who publishes or reads a channel besides the processes of the registry.
inline constexpr const char* kRunner = "runner";          // afford experiment (the front door)
inline constexpr const char* kEveryProcess = "every process";
inline constexpr const char* kAnyReceiver = "any receiver";  // RESEND: whoever misses a message

// Who publishes a channel in each phase (afford/phase.hpp, in its
// order): a process, kRunner, kEveryProcess, ... ("": not in that phase).
using Publishers = std::array<const char*, kPhases>;

// What a channel is, whatever its type.
struct ChannelInfo {
  const char* name;                    // on the bus
  Publishers publishers;               // by phase
  std::array<const char*, 4> readers;  // who takes it (the logger and the viewer aside), then nullptr
  bool recorded;                       // in the run's log
  const char* when;                    // when it goes out, in words (docs/processes-and-channels.md)
  const char* type;                    // its message type ("scene_t")
  bool serial;                         // a run message: in serial order, once, missing ones asked for

  const char* publisher(Phase phase) const { return publishers[static_cast<std::size_t>(phase)]; }
  bool in(Phase phase) const { return *publisher(phase) != '\0'; }
};

// A channel and its message type.
template <class T>
struct Channel : ChannelInfo {
  using Message = T;
  // `publishers`: intrinsic, extrinsic, goals.
  constexpr Channel(const char* name, Publishers publishers, std::array<const char*, 4> readers, bool recorded,
                    const char* when)
      : ChannelInfo{name, publishers, readers, recorded, when, wire::Bounds<T>::kName, wire::Bounds<T>::kSerial} {}
};

namespace ch {
inline constexpr Channel<run_config_t> runConfig{
    "RUN_CONFIG", {kRunner, kRunner, kRunner}, {kEveryProcess}, true,
    "once per run (again, backing off from 10 ms, while a process has not taken it)"};
inline constexpr Channel<run_control_t> runControl{
    "RUN_CONTROL", {kRunner, kRunner, kRunner}, {kEveryProcess}, true, "`START`, then `STOP` after the result"};
inline constexpr Channel<process_status_t> status{
    "STATUS", {kEveryProcess, kEveryProcess, kEveryProcess}, {kRunner, kEveryProcess}, false,
    "on every state change, twice a second, and when idle in a run (its counts tell a receiver what it missed); "
    "at once on hearing a copy of itself; the runner's beat too (as `runner`, while it drives a run)"};
inline constexpr Channel<object_probe_t> probe{
    "PROBE", {"environment", "environment", "environment"}, {"predictors"}, true,
    "once, at `START`: each object's focus image alone and centred"};
inline constexpr Channel<scene_t> scene{
    "SCENE", {"environment", "environment", "environment"}, {"eye", "planner"}, true,
    "at the start, after every executed action, when late objects appear; extrinsic: also the goal scene"};
inline constexpr Channel<focus_t> focus{
    "FOCUS", {"eye", "eye", "eye"}, {"predictors", "planner", "motivation"}, true,
    "every step: the focus image and gaze after the saliency scan; extrinsic and goals: the answer to a `LOOK`"};
inline constexpr Channel<prediction_t> prediction{
    "PREDICTION", {"predictors", "predictors", "predictors"}, {"motivation", "planner"}, true,
    "every scene scan: the 4 affordances and 4 learning-progress values, what a memory knows of the look, "
    "and the report of the update made since the previous prediction"};
inline constexpr Channel<decision_t> decision{
    "DECISION", {"motivation", "planner", "planner"}, {"environment", "eye", "predictors"}, true,
    "intrinsic: every step, act with an action or pass; extrinsic: the planner's action; goals: every step, the "
    "planner's action for its goal, or a pass"};
inline constexpr Channel<effect_t> effect{
    "EFFECT", {"eye", "eye", "eye"}, {"predictors", "motivation"}, true,
    "after an executed action: the change-driven scan and whether the affordance held"};
inline constexpr Channel<affordance_table_t> affordanceTable{
    "AFFORDANCE_TABLE", {"predictors", "predictors", "predictors"}, {kRunner}, true,
    "every `run.curve_interval` steps (from step 0) and at the end"};
inline constexpr Channel<run_result_t> result{
    "RESULT", {"predictors", "predictors", "predictors"}, {kRunner}, true,
    "once, after the last step: weights checksum, checkpoint file, action counts, the memory's figures, the last "
    "update report"};
inline constexpr Channel<look_t> look{
    "LOOK", {"", "planner", "planner"}, {"eye"}, true,
    "extrinsic: scan the goal image, look at a place of the scene, or scan the scene; goals: look at the goal "
    "place, at the goal's object, or scan the scene"};
inline constexpr Channel<forward_query_t> forwardQuery{
    "FORWARD_QUERY", {"", "planner", "planner"}, {"predictors"}, true,
    "extrinsic and goals: what would these actions do to this object?"};
inline constexpr Channel<forward_prediction_t> forwardPrediction{
    "FORWARD_PREDICTION", {"", "predictors", "predictors"}, {"planner", "motivation"}, true,
    "extrinsic and goals: predicted focus image (float32) and position per action"};
inline constexpr Channel<extrinsic_result_t> extrinsicResult{
    "EXTRINSIC_RESULT", {"", "planner", ""}, {kRunner}, true,
    "extrinsic: solved or not, completion step, actions, utility gained, per sub-goal records"};
inline constexpr Channel<goal_t> goal{
    "GOAL", {"", "", "motivation"}, {"planner"}, true,
    "goals: at the start and after each `GOAL_RESULT`, the goal the agent sets itself next"};
inline constexpr Channel<goal_result_t> goalResult{
    "GOAL_RESULT", {"", "", "planner"}, {"motivation", kRunner}, true,
    "goals: when a goal is reached, its action budget spent, or nothing to do for it: reached or not, actions"};
inline constexpr Channel<resend_t> resend{
    "RESEND", {kAnyReceiver, kAnyReceiver, kAnyReceiver}, {"the channel's publisher"}, false,
    "when messages are missing: a lost datagram, or a restarted process catching up"};
}  // namespace ch

// Every channel, in the order of docs/processes-and-channels.md's table.
inline constexpr auto kChannels =
    std::make_tuple(ch::runConfig, ch::runControl, ch::status, ch::probe, ch::scene, ch::focus, ch::prediction,
                    ch::decision, ch::effect, ch::affordanceTable, ch::result, ch::look, ch::forwardQuery,
                    ch::forwardPrediction, ch::extrinsicResult, ch::goal, ch::goalResult, ch::resend);

// Calls f(channel) for every channel, each with its own type (Channel<T>).
template <class F>
void forEachChannel(F&& f) {
  std::apply([&](const auto&... c) { (f(c), ...); }, kChannels);
}

inline constexpr std::size_t kChannelCount = std::tuple_size_v<decltype(kChannels)>;

// The channel of that name, or nullptr.
const ChannelInfo* channelNamed(const std::string& name);
// The names of every channel, or of the run channels (those with a serial).
std::vector<std::string> channelNames(bool serial_only = false);
// Is it a run channel (its messages carry a serial)?
bool isSerialChannel(const std::string& name);
// Calls f(channel) with the typed channel of that name; false if there is none.
template <class F>
bool withChannel(const std::string& name, F&& f) {
  bool found = false;
  forEachChannel([&](const auto& c) {
    if (!found && name == c.name) {
      found = true;
      f(c);
    }
  });
  return found;
}

// The channel table of docs/processes-and-channels.md, as markdown rows.
std::string protocolTable();

}  // namespace afford
