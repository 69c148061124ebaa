// What `afford watch`'s page shows of a run: a RunView (processes/viewer/feed.hpp)
// fed from the bus or a log on one thread, read as JSON by the page's server on
// others. Everything it holds is bounded, whatever the run's length: the last
// scene, focus, goal and sub-goal images, a trace of the motivation and
// threshold of the last `trace_length` steps, the learned-affordance curves
// thinned to at most `curve_points` points (every other point dropped when
// full, the interval doubled), the goals per module, and the last `most_runs`
// runs heard. Readers never block the feed for long: a snapshot copies the
// state under the lock and encodes it (PNG, JSON) outside.
#pragma once
#include <opencv2/core.hpp>

#include <array>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "viewer/feed.hpp"

namespace afford {

struct WatchLimits {
  std::size_t trace_length = 400;
  std::size_t curve_points = 512;
  std::size_t most_runs = 64;
};

class WatchState : public RunView {
 public:
  explicit WatchState(WatchLimits limits = {});

  // RunView (the feed's thread).
  void onRun(const std::string& run_id, const std::string& title) override;
  void onScene(std::int64_t step, const cv::Mat& rgb, bool goal) override;
  // Kept as it came: decoded only when a snapshot shows it (most scenes of a fast run are never shown).
  void onSceneData(std::int64_t step, const std::vector<std::uint8_t>& data, int width, int height,
                   bool goal) override;
  void onFocus(std::int64_t step, const std::vector<std::uint8_t>& image, int side, double x, double y,
               bool goal) override;
  void onPrediction(std::int64_t step, const std::array<double, 4>& affordance) override;
  void onDecision(std::int64_t step, bool acted, int action, double motivation, double threshold) override;
  void onGoal(std::int64_t step, int id, const std::string& module, const std::vector<std::uint8_t>& image, int side,
              double x, double y) override;
  void onGoalResult(std::int64_t step, int id, const std::string& module, bool reached) override;
  void onConfig(const run_config_t& m, const RunConfig& config) override;
  void onTable(const affordance_table_t& m) override;
  void onStatus(const process_status_t& m) override;
  void onResult(const run_result_t& m) override;
  void onExtrinsicResult(const extrinsic_result_t& m) override;

  // Is this the run shown (the latest whose configuration was heard)?
  bool shows(const std::string& run_id) const;

  // Forget the run shown (a log's playback seeking back); the runs heard stay.
  void clearRun();
  // Playback of a log: what the page's controls show (`last`: the log's last step).
  void setPlayback(bool playing, double speed, std::int64_t last);
  // The version changes with every change; wait() returns once it differs from `seen` or `until` passes.
  std::uint64_t version() const;
  std::uint64_t wait(std::uint64_t seen, std::chrono::steady_clock::time_point until) const;
  // Wakes every waiter (the server stopping).
  void wakeAll();

  // The page's view, as JSON text: {"version", "step", "run", "images", ...}; `with_curves`: the curves too.
  std::string snapshot(bool with_curves) const;
  std::uint64_t curvesVersion() const;
  std::int64_t step() const;
  // For sampling the channels said every step (afford watch): the shown run's phase, its step, and the
  // older of the steps of the latest focus and prediction taken (-1: none yet).
  struct Progress {
    std::string phase;
    std::int64_t step = -1, focus_and_prediction = -1;
  };
  Progress progress() const;

 private:
  struct Image {
    cv::Mat rgb;
    std::int64_t step = -1;
    double x = -1, y = -1;
    // A scene not decoded yet: its encoded bytes (shared, never changed) and size.
    std::shared_ptr<const std::vector<std::uint8_t>> encoded;
    int width = 0, height = 0;
  };
  // A decoded image at a step (and place, for a focus image).
  static Image pixels(cv::Mat rgb, std::int64_t step, double x = -1, double y = -1) {
    Image i;
    i.rgb = std::move(rgb), i.step = step, i.x = x, i.y = y;
    return i;
  }
  struct RunSeen {
    std::string id, experiment, system, phase;
    std::int64_t steps = 0, step = -1;
    std::string state = "configured";
    std::uint64_t order = 0;
  };
  struct Copy;
  void changed();  // under the lock
  void stepTo(std::int64_t step);
  RunSeen& runSeen(const std::string& id);

  WatchLimits limits_;
  mutable std::mutex mutex_;
  mutable std::condition_variable cv_;
  std::uint64_t version_ = 0, curves_version_ = 0, runs_order_ = 0;
  // The run shown.
  std::string run_id_, title_, phase_;
  std::int64_t steps_ = 0, step_ = -1;
  std::vector<std::string> object_names_;
  std::vector<std::array<double, 4>> true_affordance_;
  Image scene_, goal_scene_, focus_, sub_goal_;
  // The picture of one step (what the eye saw, what it was predicted, what was decided): the scene when
  // the latest focus came, and the decision of the focus's step. afford watch takes the focus only a few
  // times a second (sampler.hpp) while scenes and decisions come on: shown with the latest scene, its gaze
  // box would stand on a scene of later steps.
  Image seen_scene_;
  std::string seen_decision_;
  std::int64_t seen_decision_step_ = -1;
  int side_ = 21;
  std::array<double, 4> affordance_{};
  bool have_affordance_ = false;
  std::int64_t prediction_step_ = -1;
  std::string decision_, goal_text_;
  double own_goal_x_ = -1, own_goal_y_ = -1;
  std::deque<double> motivation_, threshold_;
  std::vector<std::pair<std::string, std::pair<int, int>>> goals_;  // module -> (reached, ended)
  // The goals phase's trace: after each goal of a module that has a goal image (not an exploration), each such
  // module's competence, the share of its last 2 x goals.window goals reached (-1: none yet).
  int goal_window_ = 0;
  WorldKind world_ = WorldKind::Grid;  // names the actions
  std::map<std::string, std::deque<bool>> recent_goals_;
  std::deque<std::array<double, 3>> competence_;
  void endRun(const std::string& run_id, std::int64_t step);
  // Learned affordances: at each kept step, objects x actions.
  std::vector<std::int64_t> curve_steps_;
  std::vector<std::vector<std::array<double, 4>>> curve_values_;
  std::int64_t curve_stride_ = 1, tables_ = 0, latest_step_ = -1;
  std::vector<std::array<double, 4>> latest_values_;
  // Steps per second (display only): (when, step) of the last few seconds.
  std::deque<std::pair<std::chrono::steady_clock::time_point, std::int64_t>> pace_;
  // Playback.
  bool playback_ = false, playing_ = false;
  double speed_ = 0;
  std::int64_t last_ = -1;
  // Runs heard, by id.
  std::map<std::string, RunSeen> runs_;
  // The last snapshot made, for the other pages sent the same state (with and without the curves).
  mutable std::uint64_t cached_version_[2] = {~std::uint64_t{0}, ~std::uint64_t{0}};
  mutable std::shared_ptr<const std::string> cached_[2];
};

}  // namespace afford
