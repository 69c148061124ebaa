// Viewer core: what a run shows, drawn as one picture. No LCM here: the
// viewer process (main.cpp) feeds it the messages it hears.
//   header:     the run (its id and phase), then its step, the last decision
//               and, in the goals phase, the goal pursued
//   top row:    the scene with the outer eye's gaze box; the goal image with
//               the inner eye's focus (extrinsic phase)
//   bottom row: the focus image and the current sub-goal, enlarged; bars of the
//               affordance predictions for the focused object; traces of the
//               motivation signal and its threshold (intrinsic phase); in the
//               goals phase, the agent's own goal (its image as the sub-goal,
//               its place boxed on the scene) and the goals reached per module
#pragma once
#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <deque>
#include <string>
#include <utility>
#include <vector>

#include "viewer/feed.hpp"

namespace afford {

// A text of the picture as drawn: what it says, the box it took (its baseline's descent included), the room it
// was given, its scale, and whether all of it is there (false: its middle left out, for "...").
struct DrawnText {
  std::string text;
  cv::Rect box, room;
  double scale = 0;
  bool whole = true;
};

struct ViewerCanvas;  // (viewer.cpp)

class Viewer : public RunView {
 public:
  explicit Viewer(std::size_t trace_length = 400);

  void onRun(const std::string& run_id, const std::string& phase) override;
  // A scene (RGB, any size); `goal`: the goal configuration of an extrinsic test.
  void onScene(std::int64_t step, const cv::Mat& rgb, bool goal) override;
  // A focus image (side x side RGB bytes) at (x, y) in scene units; `goal`: the inner eye's.
  void onFocus(std::int64_t step, const std::vector<std::uint8_t>& image, int side, double x, double y, bool goal) override;
  void onPrediction(std::int64_t step, const std::array<double, 4>& affordance) override;
  void onDecision(std::int64_t step, bool acted, int action, double motivation, double threshold) override;
  // The run's world names its actions (the grid's move and colours, the table's push, carry, topple, roll).
  void onConfig(const run_config_t& m, const RunConfig& config) override;
  // Goals phase: a goal the agent set itself (`module`: its name; image empty for an exploration), and its end.
  void onGoal(std::int64_t step, int id, const std::string& module, const std::vector<std::uint8_t>& image, int side,
              double x, double y) override;
  void onGoalResult(std::int64_t step, int id, const std::string& module, bool reached) override;

  // The whole picture, BGR, for cv::imshow or cv::imwrite; its texts into `drawn`, if given. Every text fits in
  // its room: drawn smaller if need be, then shortened in its middle.
  cv::Mat render(std::vector<DrawnText>* drawn = nullptr) const;
  std::int64_t step() const { return step_; }

 private:
  void drawImages(ViewerCanvas& c) const;
  void drawBars(ViewerCanvas& c, int x) const;
  void drawTraces(ViewerCanvas& c, int x, int y) const;

  std::string run_id_, phase_;
  std::int64_t step_ = -1;
  cv::Mat scene_, goal_;                       // RGB
  double gaze_x_ = -1, gaze_y_ = -1, goal_x_ = -1, goal_y_ = -1;
  int side_ = 21;
  cv::Mat focus_, sub_goal_;                   // RGB, side x side
  std::array<double, 4> affordance_{};
  bool have_affordance_ = false;
  std::string last_decision_;
  WorldKind world_ = WorldKind::Grid;
  std::size_t trace_length_;
  std::deque<double> motivation_, threshold_;
  // Goals phase.
  std::string goal_text_;
  double own_goal_x_ = -1, own_goal_y_ = -1;
  std::vector<std::pair<std::string, std::pair<int, int>>> reached_;  // module -> (reached, ended), in order met
};

}  // namespace afford
