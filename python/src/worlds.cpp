#include "worlds.hpp"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "afford/config.hpp"
#include "afford/process_main.hpp"
#include "environment/environment.hpp"
#include "environment/world.hpp"
#include "experiment/design/experiment_file.hpp"
#include "eye/eye.hpp"

namespace py = pybind11;

namespace afford {
namespace {

// What one step did (afford.env's info).
struct StepOutcome {
  std::int64_t step = 0;
  bool acted = false, on_object = false, succeeded = false, image_changed = false, position_changed = false;
  double goal_distance = -1.0;
};

int focusSideOf(const Focus& f) {
  int side = 0;
  while ((side + 1) * (side + 1) * 3 <= static_cast<int>(f.image.size())) ++side;
  return side;
}

// The world's actions by name, in the order of its tables: the grid's (move, turn green, ...) or the table's.
std::vector<std::string> actionNames(WorldKind kind) {
  std::vector<std::string> out;
  for (int a = 0; a < kNumActions; ++a)
    out.emplace_back(actionName(kind, a));
  return out;
}

void checkAction(int act, WorldKind kind) {
  if (act >= 0 && act <= kNumActions) return;
  std::string names;
  for (const std::string& n : actionNames(kind)) names += (names.empty() ? "" : ", ") + n;
  throw std::invalid_argument("action " + std::to_string(act) + ": 0-3 (" + names + ") or 4 (pass)");
}

// FlatAffordEnv's action `a` on a grid x grid grid over the scene: 0-4 act on what the scan found (x = y = -1);
// then, per place of the grid (row by row) and act 0-3, look at the place's centre and act. Scene units are a
// pixel's column and row over the width: a scene `rows` (its height over its width; the table's 0.75) high.
struct FlatAction {
  int act;
  double x, y;
};
FlatAction flatAction(std::int64_t a, int grid, double rows = 1.0) {
  const std::int64_t n = kNumActions + 1 + std::int64_t{kNumActions} * grid * grid;
  if (a < 0 || a >= n)
    throw std::invalid_argument("action " + std::to_string(a) + ": 0 to " + std::to_string(n - 1) +
                                " (0-4: act on what the scan found, 4 passes; then look at one of " +
                                std::to_string(grid) + " x " + std::to_string(grid) + " places and act)");
  if (a <= kNumActions) return {static_cast<int>(a), -1.0, -1.0};
  const std::int64_t cell = (a - kNumActions - 1) / kNumActions, act = (a - kNumActions - 1) % kNumActions;
  const std::int64_t row = cell / grid, col = cell % grid;
  return {static_cast<int>(act), (static_cast<double>(col) + 0.5) / grid, rows * (static_cast<double>(row) + 0.5) / grid};
}

// FlatAffordEnv's observation into `out` (H x W x C, C = 4, or 7 with a goal): the scene's RGB, the eye's
// side x side window around the gaze (scene units: over the width) as a mask channel (255 inside, clipped at the
// edges), the goal's RGB.
void writeFlat(const std::uint8_t* scene, int height, int width, double gx, double gy, int side,
               const std::uint8_t* goal, std::uint8_t* out) {
  const int channels = goal ? 7 : 4;
  const int cx = static_cast<int>(std::lround(gx * width)), cy = static_cast<int>(std::lround(gy * width));
  const int top = cy - side / 2, left = cx - side / 2;
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c) {
      const std::size_t p = static_cast<std::size_t>(r) * width + c;
      std::uint8_t* o = out + p * channels;
      o[0] = scene[3 * p], o[1] = scene[3 * p + 1], o[2] = scene[3 * p + 2];
      o[3] = (r >= top && r < top + side && c >= left && c < left + side) ? 255 : 0;
      if (goal) o[4] = goal[3 * p], o[5] = goal[3 * p + 1], o[6] = goal[3 * p + 2];
    }
}

// The environment core and the eye core of one run, driven a step at a time: the eye's bottom-up scan (or
// a look where the caller says) picks the object, the action is executed on it, the eye sees its effect,
// and the next step's scan follows, as in the agent's loop (paper Algorithm 1) without predictors.
class WorldCore {
 public:
  WorldCore(const std::string& experiment, const std::string& system, std::int64_t seed,
            const std::vector<std::string>& settings, const std::string& scenario)
      : config_(parseRunConfig(effectiveConfig(
            defaultConfigDir(), RunRequest{experiment, parseSystem(system), seed, std::nullopt, settings}))) {
    if (!scenario.empty()) scenario_ = loadScenario(defaultConfigDir(), scenario, config_);
    reset();
  }

  void reset() {
    RunConfig world = config_;  // the environment process's world: an extrinsic one starts in the scenario
    if (scenario_) world.phase = Phase::Extrinsic, world.scenario = scenario_;
    env_ = makeWorld(world);
    eye_ = std::make_unique<Eye>(config_);
    step_ = 0;
    eye_->setScene(env_->render(), env_->centres());
    if (scenario_) eye_->setGoal(env_->goalScene(), env_->goalCentres());
    eye_->scan(step_);
  }

  // Look at (x, y) first when both are >= 0 (else at what the scan found), then do `act` (0-3; 4 passes).
  StepOutcome step(int act, double x, double y) {
    checkAction(act, config_.world.kind);
    if (x >= 0 && y >= 0) eye_->lookAt(std::min(x, 1.0), std::min(y, rows()));
    const Focus f = eye_->focus();
    StepOutcome out;
    out.step = step_;
    out.acted = act < kNumActions;
    if (out.acted) {
      const ActionOutcome o = env_->execute(step_, act, f.x, f.y);
      out.on_object = o.on_object;
      out.succeeded = o.succeeded;
      const Effect e = eye_->scanEffect(step_, env_->render(), act, env_->centres());
      out.image_changed = e.image_changed;
      out.position_changed = e.position_changed;
    }
    ++step_;
    if (env_->introduceObjectsAt(step_)) eye_->setScene(env_->render(), env_->centres());
    eye_->scan(step_);
    out.goal_distance = scenario_ ? env_->goalDistance() : -1.0;
    return out;
  }

  // The observation into caller's buffers: the scene (height x width x 3), the focus (side x side x 3), the gaze.
  void observe(std::uint8_t* scene, std::uint8_t* focus, double* gaze) const {
    const cv::Mat& s = eye_->scene();
    std::memcpy(scene, s.data, s.total() * 3);
    const Focus& f = eye_->focus();
    std::memcpy(focus, f.image.data(), f.image.size());
    gaze[0] = f.x, gaze[1] = f.y;
  }

  // FlatAffordEnv's observation into `out` (writeFlat).
  void observeFlat(std::uint8_t* out) const {
    const cv::Mat& s = eye_->scene();
    const Focus& f = eye_->focus();
    writeFlat(s.data, s.rows, s.cols, f.x, f.y, focusSideOf(f), scenario_ ? env_->goalScene().data : nullptr, out);
  }
  int flatChannels() const { return scenario_ ? 7 : 4; }
  bool goalReached() const { return scenario_ && env_->goalDistance() < successDistance(); }

  std::int64_t stepCount() const { return step_; }
  std::int64_t steps() const { return config_.steps; }
  int sceneWidth() const { return config_.world.size_px; }
  int sceneHeight() const { return config_.world.rows(); }
  WorldKind kind() const { return config_.world.kind; }
  // The scene's height in scene units (over its width): 1 in the grid.
  double rows() const { return static_cast<double>(sceneHeight()) / sceneWidth(); }
  int focusSide() const { return focusSideOf(eye_->focus()); }
  double successDistance() const { return config_.planner.success_distance; }
  bool hasScenario() const { return scenario_.has_value(); }
  const cv::Mat& goalScene() const {
    if (!scenario_) throw std::runtime_error("this world has no scenario: no goal image");
    return env_->goalScene();
  }

 private:
  RunConfig config_;
  std::optional<Scenario> scenario_;
  std::unique_ptr<SimWorld> env_;  // world.kind: the grid or the table
  std::unique_ptr<Eye> eye_;
  std::int64_t step_ = 0;
};

py::array_t<std::uint8_t> image(const cv::Mat& m) {
  py::array_t<std::uint8_t> out({static_cast<py::ssize_t>(m.rows), static_cast<py::ssize_t>(m.cols),
                                 static_cast<py::ssize_t>(3)});
  std::memcpy(out.mutable_data(), m.data, m.total() * 3);
  return out;
}

py::dict infoOf(const StepOutcome& o) {
  py::dict info;
  info["step"] = o.step;
  info["acted"] = o.acted;
  info["on_object"] = o.on_object;
  info["succeeded"] = o.succeeded;
  info["image_changed"] = o.image_changed;
  info["position_changed"] = o.position_changed;
  info["goal_distance"] = o.goal_distance;
  return info;
}

// One world (afford.env.AffordEnv).
class World {
 public:
  World(const std::string& experiment, const std::string& system, std::int64_t seed,
        const std::vector<std::string>& settings, const std::string& scenario)
      : core_(experiment, system, seed, settings, scenario) {}
  void reset() { core_.reset(); }
  py::dict observation() const {
    const int w = core_.sceneWidth(), h = core_.sceneHeight(), side = core_.focusSide();
    py::array_t<std::uint8_t> scene({h, w, 3}), focus({side, side, 3});
    py::array_t<double> gaze(2);
    core_.observe(scene.mutable_data(), focus.mutable_data(), gaze.mutable_data());
    py::dict o;
    o["scene"] = scene, o["focus"] = focus, o["gaze"] = gaze;
    return o;
  }
  py::dict step(int act, double x, double y) { return infoOf(core_.step(act, x, y)); }
  py::array_t<std::uint8_t> flatObservation() const {
    py::array_t<std::uint8_t> out({core_.sceneHeight(), core_.sceneWidth(), core_.flatChannels()});
    core_.observeFlat(out.mutable_data());
    return out;
  }
  const WorldCore& core() const { return core_; }

 private:
  WorldCore core_;
};

// Threads that each keep their worlds for the worlds' whole life: a table world's camera draws only on the thread
// that made it (its OpenGL context), so each world is made, stepped, reset and destroyed on its lane's thread.
// One lane is the caller's own thread.
class Lanes {
 public:
  explicit Lanes(std::size_t n) {
    for (std::size_t i = 1; i < n; ++i) threads_.emplace_back([this, i] { work(i); });
  }
  ~Lanes() {
    {
      std::lock_guard<std::mutex> l(m_);
      stop_ = true;
    }
    go_.notify_all();
    for (auto& t : threads_) t.join();
  }
  Lanes(const Lanes&) = delete;
  Lanes& operator=(const Lanes&) = delete;
  std::size_t size() const { return threads_.size() + 1; }
  // f(lane) on every lane at once (lane 0 on this thread); returns when all have, rethrowing the first exception.
  void each(const std::function<void(std::size_t)>& f) {
    {
      std::lock_guard<std::mutex> l(m_);
      job_ = &f, pending_ = threads_.size(), error_ = nullptr, ++generation_;
    }
    go_.notify_all();
    std::exception_ptr mine;
    try {
      f(0);
    } catch (...) {
      mine = std::current_exception();
    }
    std::unique_lock<std::mutex> l(m_);
    done_.wait(l, [&] { return pending_ == 0; });
    job_ = nullptr;
    if (mine) std::rethrow_exception(mine);
    if (error_) std::rethrow_exception(error_);
  }

 private:
  void work(std::size_t lane) {
    std::uint64_t seen = 0;
    std::unique_lock<std::mutex> l(m_);
    for (;;) {
      go_.wait(l, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
      const auto* f = job_;
      l.unlock();
      std::exception_ptr e;
      try {
        (*f)(lane);
      } catch (...) {
        e = std::current_exception();
      }
      l.lock();
      if (e && !error_) error_ = e;
      if (--pending_ == 0) done_.notify_all();
    }
  }

  std::vector<std::thread> threads_;
  std::mutex m_;
  std::condition_variable go_, done_;
  const std::function<void(std::size_t)>* job_ = nullptr;
  std::uint64_t generation_ = 0;
  std::size_t pending_ = 0;
  std::exception_ptr error_;
  bool stop_ = false;
};

// Many worlds of one experiment, each with its seed, stepped together: stepFlat() takes a FlatAffordEnv
// action for each and steps them with the GIL released (on `threads` threads), writing their observations
// into one array of (worlds, H, W, C). Each world goes exactly as a World of its seed.
class Worlds {
 public:
  Worlds(const std::string& experiment, const std::string& system, const std::vector<std::int64_t>& seeds,
         const std::vector<std::string>& settings, const std::string& scenario, int threads)
      : lanes_(std::min<std::size_t>(static_cast<std::size_t>(std::max(1, threads)), std::max<std::size_t>(1, seeds.size()))) {
    if (seeds.empty()) throw std::invalid_argument("Worlds: no seeds (one world per seed)");
    worlds_.resize(seeds.size());
    try {
      forEach([&](std::size_t i) {
        worlds_[i] = std::make_unique<WorldCore>(experiment, system, seeds[i], settings, scenario);
      });
    } catch (...) {
      destroy();
      throw;
    }
  }
  ~Worlds() { destroy(); }
  Worlds(const Worlds&) = delete;
  Worlds& operator=(const Worlds&) = delete;

  std::size_t size() const { return worlds_.size(); }
  const WorldCore& front() const { return *worlds_.front(); }
  const WorldCore& world(std::size_t i) const { return const_cast<Worlds*>(this)->at(i); }

  // World `i` back at its start (on its lane).
  void reset(std::size_t i) {
    WorldCore& w = at(i);
    lanes_.each([&](std::size_t lane) {
      if (lane == laneOf(i)) w.reset();
    });
  }

  // Every world's FlatAffordEnv observation, (worlds, H, W, C).
  py::array_t<std::uint8_t> flatObservation() const {
    py::array_t<std::uint8_t> out = flatBuffer();
    for (std::size_t i = 0; i < worlds_.size(); ++i) worlds_[i]->observeFlat(flatAt(out, i));
    return out;
  }

  // One step of every world with FlatAffordEnv's actions (worlds) on a grid x grid grid, the reward
  // "success" or (goal_reward) "goal", and Gymnasium's (0.29) autoreset: a world whose episode ended is
  // reset, its next observation its first. Returns (observation, reward, terminated, truncated, info,
  // final_observations): the observation is an array the next step writes again (the caller copies it);
  // final_observations, a list with the last observation of each world that ended (None for the others),
  // or None when none did.
  py::tuple stepFlat(py::array_t<std::int64_t, py::array::c_style | py::array::forcecast> actions, int grid,
                     bool goal_reward) {
    const auto n = static_cast<py::ssize_t>(worlds_.size());
    if (actions.ndim() != 1 || actions.shape(0) != n)
      throw std::invalid_argument("actions: one per world (" + std::to_string(n) + "), not shape " +
                                  shapeText(actions));
    std::vector<FlatAction> decoded;
    for (py::ssize_t i = 0; i < n; ++i) decoded.push_back(flatAction(actions.at(i), grid, front().rows()));
    std::vector<StepOutcome> out(worlds_.size());
    std::vector<char> terminated(worlds_.size()), truncated(worlds_.size());
    if (flat_.size() == 0) flat_ = flatBuffer();  // written in place every step (the caller copies it)
    std::vector<std::vector<std::uint8_t>> last(worlds_.size());
    const std::size_t bytes = static_cast<std::size_t>(flat_.size()) / worlds_.size();
    std::vector<std::string> errors(worlds_.size());
    {
      py::gil_scoped_release free;
      forEach([&](std::size_t i) {
        try {
          WorldCore& w = *worlds_[i];
          out[i] = w.step(decoded[i].act, decoded[i].x, decoded[i].y);
          terminated[i] = goal_reward && w.goalReached();
          truncated[i] = w.stepCount() >= w.steps();
          if (terminated[i] || truncated[i]) {
            last[i].resize(bytes);
            w.observeFlat(last[i].data());
            w.reset();
          }
          w.observeFlat(flatAt(flat_, i));
        } catch (const std::exception& e) {
          errors[i] = e.what();
        }
      });
    }
    for (std::size_t i = 0; i < errors.size(); ++i)
      if (!errors[i].empty()) throw std::runtime_error("world " + std::to_string(i) + ": " + errors[i]);
    py::array_t<double> reward(n);
    py::array_t<bool> term(n), trunc(n);
    py::list finals;
    bool any = false;
    for (py::ssize_t i = 0; i < n; ++i) {
      const auto k = static_cast<std::size_t>(i);
      reward.mutable_at(i) = goal_reward ? -out[k].goal_distance : (out[k].succeeded ? 1.0 : 0.0);
      term.mutable_at(i) = terminated[k] != 0, trunc.mutable_at(i) = truncated[k] != 0;
      if (last[k].empty()) {
        finals.append(py::none());
        continue;
      }
      any = true;
      py::array_t<std::uint8_t> f({flat_.shape(1), flat_.shape(2), flat_.shape(3)});
      std::memcpy(f.mutable_data(), last[k].data(), bytes);
      finals.append(f);
    }
    return py::make_tuple(flat_, reward, term, trunc, infoArrays(out), any ? py::object(finals) : py::none());
  }

 private:
  // World i's lane: the worlds are dealt to the lanes in turn.
  std::size_t laneOf(std::size_t i) const { return i % lanes_.size(); }
  // f(i) for every world, each on its lane's thread.
  void forEach(const std::function<void(std::size_t)>& f) {
    lanes_.each([&](std::size_t lane) {
      for (std::size_t i = lane; i < worlds_.size(); i += lanes_.size()) f(i);
    });
  }
  // Every world destroyed on its lane (a table world's camera frees its buffers in its thread's OpenGL context).
  void destroy() {
    try {
      forEach([&](std::size_t i) { worlds_[i].reset(); });
    } catch (...) {  // (a destructor does not throw)
    }
    worlds_.clear();
  }
  static py::dict infoArrays(const std::vector<StepOutcome>& out) {
    const auto n = static_cast<py::ssize_t>(out.size());
    py::array_t<std::int64_t> step(n);
    py::array_t<bool> acted(n), on_object(n), succeeded(n), image_changed(n), position_changed(n);
    py::array_t<double> goal_distance(n);
    for (py::ssize_t i = 0; i < n; ++i) {
      const StepOutcome& o = out[static_cast<std::size_t>(i)];
      step.mutable_at(i) = o.step;
      acted.mutable_at(i) = o.acted, on_object.mutable_at(i) = o.on_object, succeeded.mutable_at(i) = o.succeeded;
      image_changed.mutable_at(i) = o.image_changed, position_changed.mutable_at(i) = o.position_changed;
      goal_distance.mutable_at(i) = o.goal_distance;
    }
    py::dict info;
    info["step"] = step, info["acted"] = acted, info["on_object"] = on_object, info["succeeded"] = succeeded;
    info["image_changed"] = image_changed, info["position_changed"] = position_changed;
    info["goal_distance"] = goal_distance;
    return info;
  }
  py::array_t<std::uint8_t> flatBuffer() const {
    return py::array_t<std::uint8_t>({static_cast<py::ssize_t>(worlds_.size()),
                                      static_cast<py::ssize_t>(front().sceneHeight()),
                                      static_cast<py::ssize_t>(front().sceneWidth()),
                                      static_cast<py::ssize_t>(front().flatChannels())});
  }
  static std::uint8_t* flatAt(py::array_t<std::uint8_t>& a, std::size_t i) {
    return a.mutable_data() + i * static_cast<std::size_t>(a.shape(1) * a.shape(2) * a.shape(3));
  }
  WorldCore& at(std::size_t i) {
    if (i >= worlds_.size())
      throw py::index_error("world " + std::to_string(i) + " of " + std::to_string(worlds_.size()));
    return *worlds_[i];
  }
  template <class A>
  static std::string shapeText(const A& a) {
    std::string s = "(";
    for (py::ssize_t d = 0; d < a.ndim(); ++d) s += (d ? ", " : "") + std::to_string(a.shape(d));
    return s + ")";
  }

  Lanes lanes_;
  std::vector<std::unique_ptr<WorldCore>> worlds_;
  py::array_t<std::uint8_t> flat_;  // stepFlat's observations, written in place
};

}  // namespace

void defineWorlds(py::module_& m) {
  m.def("flat_action", [](std::int64_t a, int grid, double rows) {
        if (!(rows > 0 && rows <= 16)) throw std::invalid_argument("rows " + std::to_string(rows) + ": the scene's height over its width, in (0, 16]");
        const FlatAction f = flatAction(a, grid, rows);
        return py::make_tuple(f.act, f.x, f.y);
      }, py::arg("action"), py::arg("grid"), py::arg("rows") = 1.0,
      "FlatAffordEnv's action as (act, x, y) (afford.env.flat_action); rows: the scene's height over its width.");
  m.def("flat_observation",
        [](py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast> scene, std::pair<double, double> gaze,
           int side, std::optional<py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>> goal) {
          if (scene.ndim() != 3 || scene.shape(2) != 3)
            throw std::invalid_argument("scene: H x W x 3, not shape " + std::to_string(scene.ndim()) + "-d");
          if (goal && (goal->ndim() != 3 || goal->shape(0) != scene.shape(0) || goal->shape(1) != scene.shape(1) ||
                       goal->shape(2) != 3))
            throw std::invalid_argument("goal: the scene's shape");
          const int h = static_cast<int>(scene.shape(0)), w = static_cast<int>(scene.shape(1));
          py::array_t<std::uint8_t> out({h, w, goal ? 7 : 4});
          writeFlat(scene.data(), h, w, gaze.first, gaze.second, side, goal ? goal->data() : nullptr, out.mutable_data());
          return out;
        },
        py::arg("scene"), py::arg("gaze"), py::arg("side"), py::arg("goal") = py::none(),
        "FlatAffordEnv's observation from a scene, a gaze (x, y) and the window's side (afford.env.flat_observation).");
  py::class_<World>(m, "World", "The environment and the eye of one run, a step at a time (afford.env).")
      .def(py::init<const std::string&, const std::string&, std::int64_t, const std::vector<std::string>&,
                    const std::string&>(),
           py::arg("experiment"), py::arg("system"), py::arg("seed"), py::arg("settings"), py::arg("scenario"))
      .def("reset", &World::reset)
      .def("observation", &World::observation)
      .def("step", &World::step, py::arg("act"), py::arg("x") = -1.0, py::arg("y") = -1.0)
      .def_property_readonly("step_count", [](const World& w) { return w.core().stepCount(); })
      .def_property_readonly("steps", [](const World& w) { return w.core().steps(); })
      .def_property_readonly("scene_width", [](const World& w) { return w.core().sceneWidth(); })
      .def_property_readonly("scene_height", [](const World& w) { return w.core().sceneHeight(); })
      .def_property_readonly("action_names", [](const World& w) { return actionNames(w.core().kind()); })
      .def_property_readonly("rows", [](const World& w) { return w.core().rows(); })
      .def_property_readonly("focus_side", [](const World& w) { return w.core().focusSide(); })
      .def_property_readonly("success_distance", [](const World& w) { return w.core().successDistance(); })
      .def("goal", [](const World& w) { return image(w.core().goalScene()); })
      .def("flat_observation", &World::flatObservation,
           "FlatAffordEnv's observation: H x W x C uint8, the scene, the eye's window as a mask, the goal");
  py::class_<Worlds>(m, "Worlds",
                     "Many worlds of one experiment, one per seed, stepped in one call with the GIL released "
                     "(afford.env.AffordVectorEnv).")
      .def(py::init<const std::string&, const std::string&, const std::vector<std::int64_t>&,
                    const std::vector<std::string>&, const std::string&, int>(),
           py::arg("experiment"), py::arg("system"), py::arg("seeds"), py::arg("settings"), py::arg("scenario"),
           py::arg("threads") = 1)
      .def("__len__", &Worlds::size)
      .def("reset", &Worlds::reset, py::arg("index"))
      .def("flat_observation", &Worlds::flatObservation)
      .def("step_flat", &Worlds::stepFlat, py::arg("actions"), py::arg("grid"), py::arg("goal_reward"))
      .def_property_readonly("steps", [](const Worlds& w) { return w.front().steps(); })
      .def_property_readonly("scene_width", [](const Worlds& w) { return w.front().sceneWidth(); })
      .def_property_readonly("scene_height", [](const Worlds& w) { return w.front().sceneHeight(); })
      .def_property_readonly("action_names", [](const Worlds& w) { return actionNames(w.front().kind()); })
      .def_property_readonly("focus_side", [](const Worlds& w) { return w.front().focusSide(); })
      .def_property_readonly("success_distance", [](const Worlds& w) { return w.front().successDistance(); })
      .def("goal", [](const Worlds& w, std::size_t i) { return image(w.world(i).goalScene()); }, py::arg("index"));
}

}  // namespace afford
