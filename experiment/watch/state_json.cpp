// WatchState::snapshot: the page's view as JSON, encoded outside the lock.
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sodium.h>

#include "afford/image.hpp"
#include "experiment/watch/state.hpp"

namespace afford {

using nlohmann::json;

namespace {

// An RGB image as a data: URL of a PNG.
std::string pngUrl(const cv::Mat& rgb) {
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  std::vector<std::uint8_t> png;
  cv::imencode(".png", bgr, png);
  std::string b64(sodium_base64_ENCODED_LEN(png.size(), sodium_base64_VARIANT_ORIGINAL), '\0');
  sodium_bin2base64(b64.data(), b64.size(), png.data(), png.size(), sodium_base64_VARIANT_ORIGINAL);
  b64.resize(b64.size() - 1);  // its NUL
  return "data:image/png;base64," + b64;
}

}  // namespace

// Everything a snapshot shows, copied under the lock (images share their pixels: the feed replaces, never changes them).
struct WatchState::Copy {
  json head;
  Image scene, goal_scene, focus, sub_goal;
  bool curves = false;
  std::vector<std::string> names;
  std::vector<std::array<double, 4>> truth;
  std::vector<std::int64_t> steps;
  std::vector<std::vector<std::array<double, 4>>> values;
};

std::string WatchState::snapshot(bool with_curves) const {
  Copy c;
  std::uint64_t version = 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    version = version_;
    if (cached_version_[with_curves] == version_) return *cached_[with_curves];  // made for another page

    double pace = 0;
    if (pace_.size() >= 2) {
      const double secs = std::chrono::duration<double>(pace_.back().first - pace_.front().first).count();
      if (secs > 0) pace = static_cast<double>(pace_.back().second - pace_.front().second) / secs;
    }
    json runs = json::array();
    std::vector<const RunSeen*> order;
    for (const auto& [id, r] : runs_) order.push_back(&r);
    std::sort(order.begin(), order.end(), [](const RunSeen* a, const RunSeen* b) { return a->order > b->order; });
    for (const RunSeen* r : order) {
      const bool shown = r->id == run_id_;  // (a log has no STATUS: its run's step is the step played)
      runs.push_back({{"id", r->id}, {"experiment", r->experiment}, {"system", r->system}, {"phase", r->phase},
                      {"steps", r->steps}, {"step", shown ? std::max(r->step, step_) : r->step},
                      {"state", playback_ && r->state == "configured" ? "recorded" : r->state}});
    }
    json goals = json::array();
    for (const auto& [module, counts] : goals_)
      goals.push_back({{"module", module}, {"reached", counts.first}, {"ended", counts.second}});
    c.head = {{"version", version_},
              {"curves_version", curves_version_},
              {"mode", playback_ ? "log" : "live"},
              {"step", step_},
              {"run", {{"id", run_id_}, {"title", title_}, {"phase", phase_}, {"steps", steps_}}},
              {"steps_per_second", playback_ ? speed_ : pace},
              {"side", side_},
              {"decision", focus_.step >= 0 && seen_decision_step_ == focus_.step ? seen_decision_ : decision_},
              {"goal_text", goal_text_},
              {"own_goal", {{"x", own_goal_x_}, {"y", own_goal_y_}}},
              {"affordance", have_affordance_ ? json(affordance_) : json(nullptr)},
              {"motivation", motivation_},
              {"threshold", threshold_},
              {"goals", goals},
              {"competence", competence_},
              {"goal_window", goal_window_},
              {"actions", world_ == WorldKind::Table
                              ? json(std::vector<std::string>(kTableActionNames.begin(), kTableActionNames.end()))
                              : json({"move", "green", "red", "blue"})},
              {"runs", runs}};
    if (playback_) c.head["playback"] = {{"playing", playing_}, {"speed", speed_}, {"last", last_}};
    c.scene = focus_.step >= 0 && seen_scene_.step >= 0 ? seen_scene_ : scene_;  // the picture of one step
    c.goal_scene = goal_scene_, c.focus = focus_, c.sub_goal = sub_goal_;
    if (with_curves) {
      c.curves = true;
      c.names = object_names_, c.truth = true_affordance_;
      c.steps = curve_steps_, c.values = curve_values_;
      if (latest_step_ >= 0 && (c.steps.empty() || latest_step_ > c.steps.back()))
        c.steps.push_back(latest_step_), c.values.push_back(latest_values_);
    }
  }
  auto image = [](const Image& i) -> json {
    cv::Mat rgb = i.rgb;
    if (rgb.empty() && i.encoded) {
      try {
        rgb = decodeScene(*i.encoded, i.width, i.height);
      } catch (const std::exception&) {  // (the edge checked its size; a stream that does not inflate)
        return nullptr;
      }
    }
    if (rgb.empty()) return nullptr;
    return {{"step", i.step}, {"x", i.x}, {"y", i.y}, {"width", rgb.cols}, {"height", rgb.rows}, {"png", pngUrl(rgb)}};
  };
  json& j = c.head;
  j["scene"] = image(c.scene);
  j["goal"] = image(c.goal_scene);
  j["focus"] = image(c.focus);
  j["sub_goal"] = image(c.sub_goal);
  if (c.curves) {
    std::vector<std::string> names = c.names;
    const std::size_t objects = c.values.empty() ? 0 : c.values.back().size();
    for (std::size_t i = names.size(); i < objects; ++i) names.push_back("object " + std::to_string(i));
    names.resize(objects);
    j["curves"] = {{"objects", names}, {"truth", c.truth}, {"steps", c.steps}, {"values", c.values}};
  }
  auto text = std::make_shared<const std::string>(j.dump(-1, ' ', false, json::error_handler_t::replace));
  std::lock_guard<std::mutex> lock(mutex_);
  cached_version_[with_curves] = version, cached_[with_curves] = text;
  return *text;
}

}  // namespace afford
