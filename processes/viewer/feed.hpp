// What a watcher of a run hears, turned into the calls of a RunView: the
// viewer's window and frames, `afford render`'s video and `afford watch`'s page
// all take a run the same way, live from a bus (through the edge) or from a
// recorded log (each event decoded and checked as the edge would).
#pragma once
#include <opencv2/core.hpp>
#include <spdlog/spdlog.h>

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "afford/affordance_table_t.hpp"
#include "afford/extrinsic_result_t.hpp"
#include "afford/config.hpp"
#include "afford/edge.hpp"
#include "afford/logfile.hpp"
#include "afford/process_status_t.hpp"
#include "afford/run_config_t.hpp"
#include "afford/run_result_t.hpp"

namespace afford {

// One run as a watcher sees it. The first seven calls are the viewer's; the
// rest tell a page more (each does nothing unless overridden).
class RunView {
 public:
  virtual ~RunView() = default;
  virtual void onRun(const std::string& run_id, const std::string& title) = 0;
  virtual void onScene(std::int64_t step, const cv::Mat& rgb, bool goal) = 0;
  // A scene as it came (encoding scene_t::ENCODING_*): decoded, then onScene. A view that draws only some
  // scenes keeps the bytes and decodes those it draws. Throws std::runtime_error if it does not decode.
  virtual void onSceneData(std::int64_t step, const std::vector<std::uint8_t>& data, int width, int height, bool goal);
  virtual void onFocus(std::int64_t step, const std::vector<std::uint8_t>& image, int side, double x, double y,
                       bool goal) = 0;
  virtual void onPrediction(std::int64_t step, const std::array<double, 4>& affordance) = 0;
  virtual void onDecision(std::int64_t step, bool acted, int action, double motivation, double threshold) = 0;
  virtual void onGoal(std::int64_t step, int id, const std::string& module, const std::vector<std::uint8_t>& image,
                      int side, double x, double y) = 0;
  virtual void onGoalResult(std::int64_t step, int id, const std::string& module, bool reached) = 0;
  // The run's configuration as taken (after onRun), a learned-affordance table, a process's status (any run), a
  // run's result (any run: an intrinsic or goals run's, an extrinsic test's).
  virtual void onConfig(const run_config_t&, const RunConfig&) {}
  virtual void onTable(const affordance_table_t&) {}
  virtual void onStatus(const process_status_t&) {}
  virtual void onResult(const run_result_t&) {}
  virtual void onExtrinsicResult(const extrinsic_result_t&) {}
};

// The name of a goal module (goal_t.module), "?" for another value.
std::string goalModuleName(int module);

// Feeds one RunView with one run: the last RUN_CONFIG's (any run until one is
// heard; from a log, the first run unless `run_id` names one).
class ViewFeed {
 public:
  // `log`: where "showing run '...'" is said of each new run shown (nowhere if null).
  ViewFeed(RunView& view, const ProtocolConfig& protocol, std::string run_id = "", spdlog::logger* log = nullptr);

  // Live: takes every channel the view needs from `edge` (a passive listener: it asks for nothing missed).
  // `effects`: EFFECT too, the gaze of the scan after an action until the next FOCUS (a view drawn a few
  // times a second does without it, and a listener of fewer messages costs the run less).
  void subscribe(Edge& edge, bool effects = true);

  // From a log: one recorded event. False, with why, if the edge would refuse it; other runs' events and
  // channels the view does not take are passed over (true).
  bool take(const LogEvent& event, std::string& why);

  const std::string& shown() const { return shown_; }
  const RunConfig& config() const { return config_; }

 private:
  template <class Msg>
  std::string handle(const Msg& m);
  std::string handleConfig(const run_config_t& m, Edge* edge);

  RunView& view_;
  const ProtocolConfig& protocol_;
  spdlog::logger* log_;
  std::string wanted_, shown_;
  RunConfig config_;
  bool have_config_ = false;
};

}  // namespace afford
