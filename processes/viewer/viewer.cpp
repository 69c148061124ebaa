#include "viewer/viewer.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstdio>

#include "afford/actions.hpp"

namespace afford {
namespace {

const int kPanel = 300;   // side of a scene panel in pixels
const int kSmall = 150;   // side of the focus and sub-goal panels
const int kTop = 56;      // the header's two lines, above the panels
const int kBars = 300;    // width of the right column: the affordance bars and the traces
const double kSmallest = 0.35;  // a text is drawn no smaller than this scale to fit its room
const int kFont = cv::FONT_HERSHEY_SIMPLEX;
const cv::Scalar kBackground(40, 40, 40), kText(230, 230, 230), kGaze(0, 255, 255), kInner(255, 0, 255);

int widthOf(const std::string& text, double scale) {
  int baseline = 0;
  return cv::getTextSize(text, kFont, scale, 1, &baseline).width;
}

}  // namespace

// The picture being drawn, and its texts as drawn.
struct ViewerCanvas {
  cv::Mat out;
  std::vector<DrawnText>* drawn;

  // `text` drawn from `at` (the left end of its baseline) within `room` pixels: at `scale`, or smaller, down to
  // kSmallest, so that all of it fits; past that, its middle is left out for "..." (a run id of 200 bytes).
  void label(const std::string& text, cv::Point at, int room, double scale = 0.5) {
    double s = scale;
    for (int width = widthOf(text, s); width > room && s > kSmallest; width = widthOf(text, s))
      s = std::max(kSmallest, std::min(s - 0.01, s * room / width));
    std::string shown = text, head = text.substr(0, text.size() / 2), tail = text.substr(text.size() / 2);
    while (widthOf(shown, s) > room && !(head.empty() && tail.empty())) {
      if (head.size() >= tail.size())
        head.pop_back();
      else
        tail.erase(0, 1);
      shown = head + "..." + tail;
    }
    cv::putText(out, shown, at, kFont, s, kText, 1, cv::LINE_AA);
    if (!drawn) return;
    int baseline = 0;
    const cv::Size size = cv::getTextSize(shown, kFont, s, 1, &baseline);
    drawn->push_back({text, cv::Rect(at.x, at.y - size.height, size.width, size.height + baseline),
                      cv::Rect(at.x, at.y - size.height, room, size.height + baseline), s, shown == text});
  }
};

namespace {

// An RGB image enlarged (nearest neighbour) into a BGR panel of `out` at `where`; or, grey, `empty`.
// The part of a panel an image fills with its own proportions (a scene of the table world is 4:3), centred.
cv::Rect fitted(const cv::Mat& rgb, const cv::Rect& where) {
  if (rgb.empty() || rgb.cols == rgb.rows) return where;
  if (rgb.cols > rgb.rows) {
    const int h = where.width * rgb.rows / rgb.cols;
    return {where.x, where.y + (where.height - h) / 2, where.width, h};
  }
  const int w = where.height * rgb.cols / rgb.rows;
  return {where.x + (where.width - w) / 2, where.y, w, where.height};
}

void panel(ViewerCanvas& c, const cv::Mat& rgb, const cv::Rect& where, const std::string& empty) {
  if (rgb.empty()) {
    c.out(where).setTo(cv::Scalar(70, 70, 70));
    c.label(empty, cv::Point(where.x + 10, where.y + where.height / 2), where.width - 20);
    return;
  }
  const cv::Rect shown = fitted(rgb, where);
  if (shown != where) c.out(where).setTo(cv::Scalar(70, 70, 70));
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  cv::resize(bgr, c.out(shown), shown.size(), 0, 0, cv::INTER_NEAREST);
}

void box(cv::Mat m, double x, double y, double side_units, const cv::Scalar& colour) {
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

void Viewer::onConfig(const run_config_t&, const RunConfig& config) { world_ = config.world.kind; }

void Viewer::onDecision(std::int64_t step, bool acted, int action, double motivation, double threshold) {
  motivation_.push_back(motivation);
  threshold_.push_back(threshold);
  while (motivation_.size() > trace_length_) motivation_.pop_front(), threshold_.pop_front();
  last_decision_ = acted && validAction(action) ? "act: " + std::string(actionName(world_, action)) : "pass";
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

cv::Mat Viewer::render(std::vector<DrawnText>* drawn) const {
  const int w = 2 * kPanel + 3 * 10 + kBars + 20, h = kTop + kPanel + 2 * 180 + 20;
  ViewerCanvas c{cv::Mat(h, w, CV_8UC3, kBackground), drawn};
  if (drawn) drawn->clear();
  // The header: the run, then where it is.
  c.label((run_id_.empty() ? "(no run yet)" : run_id_) + "  " + phase_, cv::Point(10, kTop - 34), w - 20, 0.55);
  std::string now = "step " + std::to_string(step_);
  for (const std::string* part : {&last_decision_, &goal_text_})
    if (!part->empty()) now += "  " + *part;
  c.label(now, cv::Point(10, kTop - 10), w - 20);
  drawImages(c);
  drawBars(c, 30 + 2 * kPanel);
  drawTraces(c, 30 + 2 * kPanel, kTop + 190);
  return c.out;
}

// The scene with the gaze box, the goal image with the inner eye's focus; the focus image and the sub-goal.
void Viewer::drawImages(ViewerCanvas& c) const {
  const double focus_units = static_cast<double>(side_) / std::max(1, scene_.empty() ? 150 : scene_.cols);
  const cv::Rect scene(10, kTop, kPanel, kPanel), goal(20 + kPanel, kTop, kPanel, kPanel);
  panel(c, scene_, scene, "no scene yet");
  // Places are scene units (a column or row over the image's width): boxed on the image as drawn.
  box(c.out(fitted(scene_, scene)), gaze_x_, gaze_y_, focus_units, kGaze);
  if (own_goal_x_ >= 0) box(c.out(fitted(scene_, scene)), own_goal_x_, own_goal_y_, focus_units, kInner);
  c.label(own_goal_x_ >= 0 ? "scene (yellow: gaze, magenta: goal)" : "scene (yellow: gaze)",
          cv::Point(scene.x, scene.br().y + 18), kPanel);
  const bool extrinsic = phase_.rfind("extrinsic", 0) == 0, goals = phase_.rfind("goals", 0) == 0;
  panel(c, goal_, goal, extrinsic ? "no goal yet" : goals ? "its own goals: on the scene" : "no goal (intrinsic phase)");
  box(c.out(fitted(goal_, goal)), goal_x_, goal_y_, focus_units, kInner);
  c.label("goal (magenta: inner eye)", cv::Point(goal.x, goal.br().y + 18), kPanel);
  const cv::Rect focus(10, kTop + kPanel + 30, kSmall, kSmall), sub_goal(20 + kSmall, focus.y, kSmall, kSmall);
  panel(c, focus_, focus, "no focus");
  c.label("focus", cv::Point(focus.x, focus.br().y + 16), kSmall);
  panel(c, sub_goal_, sub_goal, "no sub-goal");
  c.label("sub-goal", cv::Point(sub_goal.x, sub_goal.br().y + 16), kSmall);
}

// The affordance bars of the focused object, from x.
void Viewer::drawBars(ViewerCanvas& c, int x) const {
  const int bh = 150;
  cv::rectangle(c.out, cv::Rect(x, kTop, kBars, bh), cv::Scalar(70, 70, 70), cv::FILLED);
  c.label("affordance of the focused object", cv::Point(x, kTop + bh + 18), kBars);
  const cv::Scalar colours[4] = {cv::Scalar(200, 200, 200), cv::Scalar(0, 200, 0), cv::Scalar(0, 0, 220),
                                 cv::Scalar(220, 0, 0)};
  // The grid's colour actions by their colours' short names; the table's by their own.
  const std::array<std::string_view, 4> names =
      world_ == WorldKind::Table ? kTableActionNames : std::array<std::string_view, 4>{"move", "green", "red", "blue"};
  for (int a = 0; a < 4; ++a) {
    const int x0 = x + 15 + a * 72, top = kTop + 10, height = bh - 40;
    const int bar = have_affordance_ ? static_cast<int>(std::clamp(affordance_[a], 0.0, 1.0) * height) : 0;
    cv::rectangle(c.out, cv::Rect(x0, top + height - bar, 50, bar), colours[a], cv::FILLED);
    cv::line(c.out, cv::Point(x0 - 4, top + height / 2), cv::Point(x0 + 54, top + height / 2), cv::Scalar(120, 120, 120));
    c.label(std::string(names[static_cast<std::size_t>(a)]), cv::Point(x0, top + height + 18), 66, 0.45);
  }
}

// The motivation and threshold traces (intrinsic phase), or the goals reached per module (goals phase), at (x, y).
void Viewer::drawTraces(ViewerCanvas& c, int x, int y) const {
  const int tw = kBars, th = 160;
  const bool goals = phase_.rfind("goals", 0) == 0;
  cv::rectangle(c.out, cv::Rect(x, y, tw, th), cv::Scalar(70, 70, 70), cv::FILLED);
  c.label(goals ? "its goals, per module" : "motivation (white) and threshold (orange)", cv::Point(x, y + th + 18), tw,
          0.45);
  double top = 1e-9;
  for (std::size_t i = 0; i < motivation_.size(); ++i) top = std::max({top, motivation_[i], threshold_[i]});
  auto trace = [&](const std::deque<double>& v, const cv::Scalar& colour) {
    for (std::size_t i = 1; i < v.size(); ++i) {
      const auto px = [&](std::size_t k, double val) {
        return cv::Point(x + static_cast<int>(k * (tw - 1) / std::max<std::size_t>(1, trace_length_ - 1)),
                         y + th - 1 - static_cast<int>(val / top * (th - 2)));
      };
      cv::line(c.out, px(i - 1, v[i - 1]), px(i, v[i]), colour, 1, cv::LINE_AA);
    }
  };
  trace(motivation_, cv::Scalar(255, 255, 255));
  trace(threshold_, cv::Scalar(0, 140, 255));
  int line = 0;
  for (const auto& [module, counts] : reached_)  // goals phase: its goals, reached of ended, per module
    c.label(module + ": " + std::to_string(counts.first) + " of " + std::to_string(counts.second) + " reached",
            cv::Point(x + 10, y + 40 + 20 * line++), tw - 20, 0.45);
  char scale[64];
  std::snprintf(scale, sizeof scale, "max %.3g", top);
  if (!goals) c.label(scale, cv::Point(x + 5, y + 15), tw - 10, 0.4);
}

}  // namespace afford
