#include "viewer/feed.hpp"

#include "afford/decision_t.hpp"
#include "afford/decode.hpp"
#include "afford/effect_t.hpp"
#include "afford/focus_t.hpp"
#include "afford/goal_result_t.hpp"
#include "afford/goal_t.hpp"
#include "afford/image.hpp"
#include "afford/names.hpp"
#include "afford/prediction_t.hpp"
#include "afford/protocol.hpp"
#include "afford/scene_t.hpp"

namespace afford {

std::string goalModuleName(int module) {
  static const char* names[] = {"explore", "colour", "move", "colour and place"};
  return module >= 0 && module < 4 ? names[module] : "?";
}

void RunView::onSceneData(std::int64_t step, const std::vector<std::uint8_t>& data, int width, int height, bool goal) {
  onScene(step, decodeScene(data, width, height), goal);
}

ViewFeed::ViewFeed(RunView& view, const ProtocolConfig& protocol, std::string run_id, spdlog::logger* log)
    : view_(view), protocol_(protocol), log_(log), wanted_(std::move(run_id)) {}

std::string ViewFeed::handleConfig(const run_config_t& m, Edge* edge) {
  RunConfig parsed;
  try {
    parsed = parseRunConfigText(m.config_yaml);
  } catch (const std::exception& e) {
    return std::string("its configuration is refused: ") + e.what();
  }
  if (m.run_id == shown_) return "";  // the runner says a run's configuration more than once
  config_ = std::move(parsed);
  have_config_ = true;
  shown_ = m.run_id;
  if (edge) edge->join(m.run_id, &config_, requestOf(m));
  view_.onRun(m.run_id, std::string(nameOf(kPhaseNames, config_.phase)) + " " + m.experiment + " " + m.system);
  view_.onConfig(m, config_);
  if (log_) log_->info("showing run '{}'", m.run_id);
  return "";
}

template <>
std::string ViewFeed::handle(const scene_t& m) {
  try {
    view_.onSceneData(m.step, m.data, m.width, m.height, m.cause == scene_t::CAUSE_GOAL);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}
template <>
std::string ViewFeed::handle(const focus_t& m) {
  view_.onFocus(m.step, m.image, m.side, m.x, m.y, m.kind == focus_t::GOAL_SCAN);
  return "";
}
template <>
std::string ViewFeed::handle(const prediction_t& m) {
  view_.onPrediction(m.step, {m.affordance[0], m.affordance[1], m.affordance[2], m.affordance[3]});
  return "";
}
template <>
std::string ViewFeed::handle(const effect_t& m) {  // the gaze after the change-driven scan
  view_.onFocus(m.step, m.image, m.side, m.after_x, m.after_y, false);
  return "";
}
template <>
std::string ViewFeed::handle(const goal_t& m) {
  view_.onGoal(m.step, m.id, goalModuleName(m.module), m.image, config_.eye.focus_side, m.x, m.y);
  return "";
}
template <>
std::string ViewFeed::handle(const goal_result_t& m) {
  view_.onGoalResult(m.step, m.id, goalModuleName(m.module), m.reached);
  return "";
}
template <>
std::string ViewFeed::handle(const decision_t& m) {
  view_.onDecision(m.step, m.acted, m.action, m.motivation, m.threshold);
  return "";
}
template <>
std::string ViewFeed::handle(const affordance_table_t& m) {
  view_.onTable(m);
  return "";
}
template <>
std::string ViewFeed::handle(const process_status_t& m) {
  view_.onStatus(m);
  return "";
}
template <>
std::string ViewFeed::handle(const run_result_t& m) {
  view_.onResult(m);
  return "";
}
template <>
std::string ViewFeed::handle(const extrinsic_result_t& m) {
  view_.onExtrinsicResult(m);
  return "";
}

namespace {
template <class F>
Turn turnOf(F&& f) {
  std::string why = f();
  return why.empty() ? Turn::take() : Turn::refuse(why);
}
}  // namespace

void ViewFeed::subscribe(Edge& edge, bool effects) {
  edge.warnOtherRuns(false);
  edge.subscribe(ch::runConfig, [this, &edge](const run_config_t& m) { return turnOf([&] { return handleConfig(m, &edge); }); },
                 Scope::Any, Order::None);
  // Every run's status and result: the runs heard, side by side or one after the other, and when each ended.
  auto any = [&](const auto& channel) {
    using Msg = typename std::decay_t<decltype(channel)>::Message;
    edge.subscribe(channel, [this](const Msg& m) { return turnOf([&] { return handle(m); }); }, Scope::Any, Order::None);
  };
  any(ch::status);
  any(ch::result);
  any(ch::extrinsicResult);
  auto follow = [&](const auto& channel) {
    using Msg = typename std::decay_t<decltype(channel)>::Message;
    edge.subscribe(channel, [this](const Msg& m) { return turnOf([&] { return handle(m); }); }, Scope::RunOrAny,
                   Order::Follow);
  };
  follow(ch::scene);
  follow(ch::focus);
  follow(ch::prediction);
  follow(ch::decision);
  if (effects) follow(ch::effect);
  follow(ch::goal);
  follow(ch::goalResult);
  follow(ch::affordanceTable);
}

bool ViewFeed::take(const LogEvent& e, std::string& why) {
  why.clear();
  bool taken = true;
  const BoundsContext ctx{&protocol_, have_config_ ? &config_ : nullptr};
  withChannel(e.channel, [&](const auto& c) {
    using Msg = typename std::decay_t<decltype(c)>::Message;
    if constexpr (std::is_same_v<Msg, run_config_t>) {
      run_config_t m{};
      if (!decodeChecked(e.data.data(), e.data.size(), ctx, m, why)) return void(taken = false);
      if (!wanted_.empty() ? m.run_id != wanted_ : !shown_.empty() && m.run_id != shown_) return;
      why = handleConfig(m, nullptr);
      taken = why.empty();
    } else if constexpr (std::is_same_v<Msg, scene_t> || std::is_same_v<Msg, focus_t> ||
                         std::is_same_v<Msg, prediction_t> || std::is_same_v<Msg, decision_t> ||
                         std::is_same_v<Msg, effect_t> || std::is_same_v<Msg, goal_t> ||
                         std::is_same_v<Msg, goal_result_t> || std::is_same_v<Msg, affordance_table_t> ||
                         std::is_same_v<Msg, run_result_t> || std::is_same_v<Msg, extrinsic_result_t> ||
                         std::is_same_v<Msg, process_status_t>) {
      std::string run;
      if (!have_config_ || !peekRunId(e.data.data(), e.data.size(), protocol_.limits.name_bytes, run) ||
          run != shown_)
        return;  // another run's, or before the run's configuration
      Msg m;
      if (!decodeChecked(e.data.data(), e.data.size(), ctx, m, why)) return void(taken = false);
      why = handle(m);
      taken = why.empty();
    }
  });
  return taken;
}

}  // namespace afford
