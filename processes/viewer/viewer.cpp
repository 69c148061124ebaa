#include "viewer/viewer.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstdio>

#include "afford/actions.hpp"

namespace afford {
namespace {

const int kPanel = 300;  // side of a scene panel in pixels
const cv::Scalar kBackground(40, 40, 40), kText(230, 230, 230), kGaze(0, 255, 255), kInner(255, 0, 255);

void label(cv::Mat& m, const std::string& text, cv::Point at, double scale = 0.5) {
  cv::putText(m, text, at, cv::FONT_HERSHEY_SIMPLEX, scale, kText, 1, cv::LINE_AA);
}

// An RGB image enlarged (nearest neighbour) into a BGR panel, or a grey "nothing yet".
cv::Mat panel(const cv::Mat& rgb, int side, const char* empty) {
  cv::Mat out(side, side, CV_8UC3, cv::Scalar(70, 70, 70));
  if (rgb.empty()) {
    label(out, empty, cv::Point(10, side / 2));
    return out;
  }
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  cv::resize(bgr, out, cv::Size(side, side), 0, 0, cv::INTER_NEAREST);
  return out;
}

void box(cv::Mat& m, double x, double y, double side_units, const cv::Scalar& colour) {
  if (x < 0) return;
  const int s = m.cols;
  const int half = static_cast<int>(side_units * s / 2);
  const cv::Point c(static_cast<int>(x * s), static_cast<int>(y * s));
  cv::rectangle(m, c - cv::Point(half, half), c + cv::Point(half, half), colour, 2);
}

}  // namespace

Viewer::Viewer(std::size_t trace_length) : trace_length_(trace_length) {}

void Viewer::onRun(const std::string& run_id, const std::string& phase) {
  *this = Viewer(trace_length_);
  run_id_ = run_id;
  phase_ = phase;
}

void Viewer::onScene(std::int64_t step, const cv::Mat& rgb, bool goal) {
  (goal ? goal_ : scene_) = rgb.clone();
  step_ = std::max(step_, step);
}

void Viewer::onFocus(std::int64_t step, const std::vector<std::uint8_t>& image, int side, double x, double y,
                     bool goal) {
  if (side <= 0 || image.size() != static_cast<std::size_t>(side * side * 3)) return;
  side_ = side;
  cv::Mat m = cv::Mat(side, side, CV_8UC3, const_cast<std::uint8_t*>(image.data())).clone();
  if (goal) {
    sub_goal_ = m;
    goal_x_ = x, goal_y_ = y;
  } else {
    focus_ = m;
    gaze_x_ = x, gaze_y_ = y;
  }
  step_ = std::max(step_, step);
}

void Viewer::onPrediction(std::int64_t step, const std::array<double, 4>& affordance) {
  affordance_ = affordance;
  have_affordance_ = true;
  step_ = std::max(step_, step);
}

void Viewer::onDecision(std::int64_t step, bool acted, int action, double motivation, double threshold) {
  motivation_.push_back(motivation);
  threshold_.push_back(threshold);
  while (motivation_.size() > trace_length_) motivation_.pop_front(), threshold_.pop_front();
  last_decision_ = acted && action >= 0 && action < kNumActions ? "act: " + std::string(kActionNames[action]) : "pass";
  step_ = std::max(step_, step);
}

void Viewer::onGoal(std::int64_t step, int id, const std::string& module, const std::vector<std::uint8_t>& image,
                    int side, double x, double y) {
  goal_text_ = "goal " + std::to_string(id) + ": " + module;
  own_goal_x_ = x, own_goal_y_ = y;
  sub_goal_ = cv::Mat();
  if (side > 0 && image.size() == static_cast<std::size_t>(side * side * 3))
    sub_goal_ = cv::Mat(side, side, CV_8UC3, const_cast<std::uint8_t*>(image.data())).clone();
  step_ = std::max(step_, step);
}

void Viewer::onGoalResult(std::int64_t step, int id, const std::string& module, bool reached) {
  goal_text_ = "goal " + std::to_string(id) + ": " + module + (reached ? " reached" : " not reached");
  auto it = std::find_if(reached_.begin(), reached_.end(), [&](const auto& r) { return r.first == module; });
  if (it == reached_.end()) it = reached_.insert(reached_.end(), {module, {0, 0}});
  it->second.first += reached ? 1 : 0;
  ++it->second.second;
  step_ = std::max(step_, step);
}

cv::Mat Viewer::render() const {
  const int w = 2 * kPanel + 3 * 10 + 320, h = kPanel + 2 * 180 + 60;
  cv::Mat out(h, w, CV_8UC3, kBackground);
  char head[256];
  std::snprintf(head, sizeof head, "%s  %s  step %lld  %s  %s", run_id_.empty() ? "(no run yet)" : run_id_.c_str(),
                phase_.c_str(), static_cast<long long>(step_), last_decision_.c_str(), goal_text_.c_str());
  label(out, head, cv::Point(10, 22), 0.55);
  const double focus_units = static_cast<double>(side_) / std::max(1, scene_.empty() ? 150 : scene_.cols);

  // Scene with the gaze box; goal image with the inner eye's focus.
  cv::Mat scene = panel(scene_, kPanel, "no scene yet");
  box(scene, gaze_x_, gaze_y_, focus_units, kGaze);
  if (own_goal_x_ >= 0) box(scene, own_goal_x_, own_goal_y_, focus_units, kInner);
  scene.copyTo(out(cv::Rect(10, 40, kPanel, kPanel)));
  label(out, own_goal_x_ >= 0 ? "scene (yellow: gaze, magenta: goal)" : "scene (yellow: gaze)",
        cv::Point(10, 40 + kPanel + 18));
  const bool extrinsic = phase_.rfind("extrinsic", 0) == 0, goals = phase_.rfind("goals", 0) == 0;
  cv::Mat goal = panel(goal_, kPanel, extrinsic ? "no goal yet" : goals ? "its own goals: on the scene" : "no goal (intrinsic phase)");
  box(goal, goal_x_, goal_y_, focus_units, kInner);
  goal.copyTo(out(cv::Rect(20 + kPanel, 40, kPanel, kPanel)));
  label(out, "goal (magenta: inner eye)", cv::Point(20 + kPanel, 40 + kPanel + 18));

  // Focus image and sub-goal.
  const int small = 150, y2 = 40 + kPanel + 30;
  panel(focus_, small, "no focus").copyTo(out(cv::Rect(10, y2, small, small)));
  label(out, "focus", cv::Point(10, y2 + small + 16));
  panel(sub_goal_, small, "no sub-goal").copyTo(out(cv::Rect(20 + small, y2, small, small)));
  label(out, "sub-goal", cv::Point(20 + small, y2 + small + 16));

  // Affordance bars of the focused object.
  const int bx = 30 + 2 * kPanel, bw = 300, bh = 150;
  cv::rectangle(out, cv::Rect(bx, 40, bw, bh), cv::Scalar(70, 70, 70), cv::FILLED);
  label(out, "affordance of the focused object", cv::Point(bx, 40 + bh + 18));
  const cv::Scalar colours[4] = {cv::Scalar(200, 200, 200), cv::Scalar(0, 200, 0), cv::Scalar(0, 0, 220),
                                 cv::Scalar(220, 0, 0)};
  const char* names[4] = {"move", "green", "red", "blue"};
  for (int a = 0; a < 4; ++a) {
    const int x0 = bx + 15 + a * 72, top = 40 + 10, height = bh - 40;
    const int bar = have_affordance_ ? static_cast<int>(std::clamp(affordance_[a], 0.0, 1.0) * height) : 0;
    cv::rectangle(out, cv::Rect(x0, top + height - bar, 50, bar), colours[a], cv::FILLED);
    cv::line(out, cv::Point(x0 - 4, top + height / 2), cv::Point(x0 + 54, top + height / 2), cv::Scalar(120, 120, 120));
    label(out, names[a], cv::Point(x0, top + height + 18), 0.45);
  }

  // Motivation and threshold traces.
  const int tx = bx, ty = 40 + bh + 40, tw = bw, th = 160;
  cv::rectangle(out, cv::Rect(tx, ty, tw, th), cv::Scalar(70, 70, 70), cv::FILLED);
  label(out, goals ? "its goals, per module" : "motivation (white) and threshold (orange)", cv::Point(tx, ty + th + 18),
        0.45);
  double top = 1e-9;
  for (std::size_t i = 0; i < motivation_.size(); ++i) top = std::max({top, motivation_[i], threshold_[i]});
  auto trace = [&](const std::deque<double>& v, const cv::Scalar& colour) {
    for (std::size_t i = 1; i < v.size(); ++i) {
      const auto px = [&](std::size_t k, double val) {
        return cv::Point(tx + static_cast<int>(k * (tw - 1) / std::max<std::size_t>(1, trace_length_ - 1)),
                         ty + th - 1 - static_cast<int>(val / top * (th - 2)));
      };
      cv::line(out, px(i - 1, v[i - 1]), px(i, v[i]), colour, 1, cv::LINE_AA);
    }
  };
  trace(motivation_, cv::Scalar(255, 255, 255));
  trace(threshold_, cv::Scalar(0, 140, 255));
  int line = 0;
  for (const auto& [module, counts] : reached_) {  // goals phase: its goals, reached of ended, per module
    char text[96];
    std::snprintf(text, sizeof text, "%s: %d of %d goals reached", module.c_str(), counts.first, counts.second);
    label(out, text, cv::Point(tx + 10, ty + 40 + 20 * line++), 0.45);
  }
  char scale[64];
  std::snprintf(scale, sizeof scale, "max %.3g", top);
  if (!goals) label(out, scale, cv::Point(tx + 5, ty + 15), 0.4);
  return out;
}

}  // namespace afford
