#include "experiment/watch/state.hpp"

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>

#include "afford/actions.hpp"
#include "afford/names.hpp"

namespace afford {

using Clock = std::chrono::steady_clock;
using nlohmann::json;

WatchState::WatchState(WatchLimits limits) : limits_(limits) {}

void WatchState::changed() {
  ++version_;
  cv_.notify_all();
}

void WatchState::stepTo(std::int64_t step) {
  if (step <= step_) return;
  step_ = step;
  if (playback_) return;
  const auto now = Clock::now();
  pace_.emplace_back(now, step);
  while (pace_.size() > 2 && now - pace_.front().first > std::chrono::seconds(3)) pace_.pop_front();
}

WatchState::RunSeen& WatchState::runSeen(const std::string& id) {
  auto [it, added] = runs_.try_emplace(id);
  if (added) {
    it->second.id = id;
    it->second.order = ++runs_order_;
    if (runs_.size() > limits_.most_runs) {  // the run heard first goes
      auto oldest = std::min_element(runs_.begin(), runs_.end(),
                                     [](const auto& a, const auto& b) { return a.second.order < b.second.order; });
      if (oldest != it) runs_.erase(oldest);
    }
  }
  return it->second;
}

void WatchState::onRun(const std::string& run_id, const std::string& title) {
  std::lock_guard<std::mutex> lock(mutex_);
  run_id_ = run_id;
  title_ = title;
  steps_ = 0, step_ = -1;
  object_names_.clear(), true_affordance_.clear();
  scene_ = goal_scene_ = focus_ = sub_goal_ = seen_scene_ = Image{};
  seen_decision_.clear(), seen_decision_step_ = -1;
  have_affordance_ = false;
  prediction_step_ = -1;
  decision_.clear(), goal_text_.clear();
  own_goal_x_ = own_goal_y_ = -1;
  motivation_.clear(), threshold_.clear(), goals_.clear();
  recent_goals_.clear(), competence_.clear();
  curve_steps_.clear(), curve_values_.clear();
  curve_stride_ = 1, tables_ = 0, latest_step_ = -1;
  latest_values_.clear();
  pace_.clear();
  ++curves_version_;
  changed();
}

void WatchState::clearRun() { onRun("", ""); }

void WatchState::onConfig(const run_config_t& m, const RunConfig& config) {
  std::lock_guard<std::mutex> lock(mutex_);
  phase_ = nameOf(kPhaseNames, config.phase);
  steps_ = config.steps;
  goal_window_ = config.goals.window;
  world_ = config.world.kind;
  for (const ObjectSpec& o : config.world.objects) {
    object_names_.push_back(o.name);
    true_affordance_.push_back(o.affordance);
  }
  RunSeen& r = runSeen(m.run_id);
  r.experiment = m.experiment, r.system = m.system, r.phase = phase_, r.steps = config.steps;
  changed();
}

void WatchState::onScene(std::int64_t step, const cv::Mat& rgb, bool goal) {
  std::lock_guard<std::mutex> lock(mutex_);
  (goal ? goal_scene_ : scene_) = pixels(rgb.clone(), step);
  stepTo(step);
  changed();
}

void WatchState::onSceneData(std::int64_t step, const std::vector<std::uint8_t>& data, int width, int height,
                             bool goal) {
  Image scene;
  scene.step = step;
  scene.encoded = std::make_shared<const std::vector<std::uint8_t>>(data);
  scene.width = width, scene.height = height;
  std::lock_guard<std::mutex> lock(mutex_);
  (goal ? goal_scene_ : scene_) = std::move(scene);
  stepTo(step);
  changed();
}

void WatchState::onFocus(std::int64_t step, const std::vector<std::uint8_t>& image, int side, double x, double y,
                         bool goal) {
  if (side <= 0 || image.size() != static_cast<std::size_t>(side) * side * 3) return;
  std::lock_guard<std::mutex> lock(mutex_);
  side_ = side;
  cv::Mat m = cv::Mat(side, side, CV_8UC3, const_cast<std::uint8_t*>(image.data())).clone();
  (goal ? sub_goal_ : focus_) = pixels(m, step, x, y);
  if (!goal) seen_scene_ = scene_;  // (shares its pixels)
  stepTo(step);
  changed();
}

void WatchState::onPrediction(std::int64_t step, const std::array<double, 4>& affordance) {
  std::lock_guard<std::mutex> lock(mutex_);
  affordance_ = affordance;
  have_affordance_ = true;
  prediction_step_ = step;
  stepTo(step);
  changed();
}

void WatchState::onDecision(std::int64_t step, bool acted, int action, double motivation, double threshold) {
  std::lock_guard<std::mutex> lock(mutex_);
  motivation_.push_back(motivation);
  threshold_.push_back(threshold);
  while (motivation_.size() > limits_.trace_length) motivation_.pop_front(), threshold_.pop_front();
  decision_ = acted && validAction(action) ? "act: " + std::string(actionName(world_, action)) : "pass";
  if (step == focus_.step) seen_decision_ = decision_, seen_decision_step_ = step;
  stepTo(step);
  changed();
}

void WatchState::onGoal(std::int64_t step, int id, const std::string& module, const std::vector<std::uint8_t>& image,
                        int side, double x, double y) {
  std::lock_guard<std::mutex> lock(mutex_);
  goal_text_ = "goal " + std::to_string(id) + ": " + module;
  own_goal_x_ = x, own_goal_y_ = y;
  sub_goal_ = Image{};
  if (side > 0 && image.size() == static_cast<std::size_t>(side) * side * 3)
    sub_goal_ = pixels(cv::Mat(side, side, CV_8UC3, const_cast<std::uint8_t*>(image.data())).clone(), step, x, y);
  stepTo(step);
  changed();
}

void WatchState::onGoalResult(std::int64_t step, int id, const std::string& module, bool reached) {
  std::lock_guard<std::mutex> lock(mutex_);
  goal_text_ = "goal " + std::to_string(id) + ": " + module + (reached ? " reached" : " not reached");
  auto it = std::find_if(goals_.begin(), goals_.end(), [&](const auto& g) { return g.first == module; });
  if (it == goals_.end()) it = goals_.insert(goals_.end(), {module, {0, 0}});
  it->second.first += reached ? 1 : 0;
  ++it->second.second;
  if (module != goalModuleName(0)) {  // an exploration has no goal image: nothing to reach
    std::deque<bool>& recent = recent_goals_[module];
    recent.push_back(reached);
    while (recent.size() > static_cast<std::size_t>(std::max(1, 2 * goal_window_))) recent.pop_front();
    std::array<double, 3> point{};
    for (int m = 1; m <= 3; ++m) {
      const auto r = recent_goals_.find(goalModuleName(m));
      point[m - 1] = r == recent_goals_.end() ? -1
                     : static_cast<double>(std::count(r->second.begin(), r->second.end(), true)) / r->second.size();
    }
    competence_.push_back(point);
    while (competence_.size() > limits_.trace_length) competence_.pop_front();
  }
  stepTo(step);
  changed();
}

void WatchState::onTable(const affordance_table_t& m) {
  std::vector<std::array<double, 4>> rows;
  for (const auto& row : m.affordance) {
    std::array<double, 4> r{};
    for (std::size_t a = 0; a < r.size() && a < row.size(); ++a) r[a] = row[a];
    rows.push_back(r);
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (tables_++ % curve_stride_ == 0) {
    curve_steps_.push_back(m.step);
    curve_values_.push_back(rows);
  }
  latest_step_ = m.step;  // drawn at the curves' end until the next point kept
  latest_values_ = std::move(rows);
  if (curve_steps_.size() > limits_.curve_points) {  // every other point goes, the interval doubles
    std::size_t k = 0;
    for (std::size_t i = 0; i < curve_steps_.size(); i += 2, ++k) {
      curve_steps_[k] = curve_steps_[i];
      curve_values_[k] = std::move(curve_values_[i]);
    }
    curve_steps_.resize(k), curve_values_.resize(k);
    curve_stride_ *= 2;
  }
  ++curves_version_;
  changed();
}

void WatchState::onStatus(const process_status_t& m) {
  if (m.run_id.empty()) return;
  std::lock_guard<std::mutex> lock(mutex_);
  if (!runs_.count(m.run_id) && runs_.size() >= limits_.most_runs) return;  // not one of the runs configured
  RunSeen& r = runSeen(m.run_id);
  r.step = std::max(r.step, m.step);
  if (m.state == process_status_t::FAILED) r.state = "failed: " + m.process;
  else if (r.state.rfind("failed", 0) != 0 && r.state != "done" && m.state == process_status_t::RUNNING) r.state = "running";
  changed();
}

void WatchState::endRun(const std::string& run_id, std::int64_t step) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!runs_.count(run_id) && runs_.size() >= limits_.most_runs) return;  // not one of the runs configured
  RunSeen& r = runSeen(run_id);
  r.state = "done";
  r.step = std::max(r.step, step);
  if (run_id == run_id_) stepTo(step);
  changed();
}

void WatchState::onResult(const run_result_t& m) { endRun(m.run_id, m.step); }

void WatchState::onExtrinsicResult(const extrinsic_result_t& m) { endRun(m.run_id, m.step); }

bool WatchState::shows(const std::string& run_id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return run_id == run_id_;
}

void WatchState::setPlayback(bool playing, double speed, std::int64_t last) {
  std::lock_guard<std::mutex> lock(mutex_);
  playback_ = true, playing_ = playing, speed_ = speed, last_ = last;
  changed();
}

std::uint64_t WatchState::version() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return version_;
}

std::uint64_t WatchState::curvesVersion() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return curves_version_;
}

std::int64_t WatchState::step() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return step_;
}

WatchState::Progress WatchState::progress() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return {phase_, step_, std::min(focus_.step, prediction_step_)};
}

std::uint64_t WatchState::wait(std::uint64_t seen, Clock::time_point until) const {
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait_until(lock, until, [&] { return version_ != seen; });
  return version_;
}

void WatchState::wakeAll() {
  std::lock_guard<std::mutex> lock(mutex_);
  changed();
}

}  // namespace afford
