// afford._afford: the project's C++ behind the Python package (python/afford).
// No protocol or file format is written again in Python: a log is read by the
// project's log reader and each message decoded and checked by the edge's
// decodeChecked, then converted by the conversions afford-lcmwire generates
// from the .lcm files (afford/to_python.hpp).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <spdlog/sinks/null_sink.h>
#include <spdlog/sinks/ringbuffer_sink.h>
#include <spdlog/sinks/stdout_color_sinks.h>

#include <cstring>
#include <memory>
#include <string>

#include "afford/version.hpp"
#include "afford/config.hpp"
#include "experiment/experiment.hpp"
#include "experiment/run/group.hpp"
#include "afford/logging.hpp"
#include "afford/decode.hpp"
#include "afford/image.hpp"
#include "afford/protocol.hpp"
#include "experiment/replay/replay.hpp"
#include "afford/rng.hpp"
#include "environment/environment.hpp"
#include "eye/eye.hpp"
#include "components.hpp"
#include "afford/to_python.hpp"
#include "experiment/design/experiment_file.hpp"
#include "afford/process_main.hpp"

namespace py = pybind11;

namespace afford {
namespace {

// A scene's pixels: height x width x 3 bytes, RGB.
py::array_t<std::uint8_t> sceneImage(const scene_t& m) {
  const cv::Mat rgb = decodeScene(m.data, m.width, m.height);
  py::array_t<std::uint8_t> out({static_cast<py::ssize_t>(m.height), static_cast<py::ssize_t>(m.width),
                                 static_cast<py::ssize_t>(3)});
  std::memcpy(out.mutable_data(), rgb.data, static_cast<std::size_t>(m.height) * m.width * 3);
  return out;
}

// The messages of one run of a log: its RUN_CONFIG and every later event of
// its run id, each as (channel, utime, fields). An event its channel's type
// refuses is skipped and counted (`refused`); one of a channel the protocol
// does not have is skipped and counted (`unknown`).
py::dict readLog(const std::string& path, const std::string& run_id, const std::string& bus_key,
                 const std::vector<std::string>& channels) {
  auto log = std::make_shared<spdlog::logger>("read_log", std::make_shared<spdlog::sinks::null_sink_mt>());
  std::shared_ptr<const BusKey> key = bus_key.empty() ? nullptr : busKeyFrom(bus_key);
  // Streamed: what is held is what is kept (a log of gigabytes read for one channel holds that channel).
  RecordedLogStream in(path, *log, key.get());
  RunSelector select(run_id, path, *log);
  std::unique_ptr<RunConfig> config;
  BoundsContext ctx{nullptr, nullptr};
  py::list messages;
  std::int64_t refused = 0, unknown = 0;
  std::string first_refusal;
  LogEvent e;
  while (in.next(e)) {
    if (!select.take(e)) continue;
    if (!config) {
      config = std::make_unique<RunConfig>(parseRunConfigText(select.config().config_yaml));
      ctx = BoundsContext{&config->protocol, config.get()};
    }
    if (!channels.empty() && std::find(channels.begin(), channels.end(), e.channel) == channels.end()) continue;
    const bool known = withChannel(e.channel, [&](const auto& c) {
      typename std::decay_t<decltype(c)>::Message m;
      std::string why;
      if (!decodeChecked(e.data.data(), e.data.size(), ctx, m, why)) {
        if (refused++ == 0) first_refusal = e.channel + ": " + why;
        return;
      }
      py::dict fields = python::toPython(m);
      if constexpr (std::is_same_v<std::decay_t<decltype(m)>, scene_t>) fields["image"] = sceneImage(m);
      messages.append(py::make_tuple(e.channel, e.utime, fields));
    });
    unknown += !known;
  }
  py::dict out;
  select.check();
  out["run_id"] = select.config().run_id;
  out["config_yaml"] = select.config().config_yaml;
  out["messages"] = messages;
  out["refused"] = refused;
  out["first_refusal"] = first_refusal;
  out["unknown_channels"] = unknown;
  out["malformed"] = in.counts().malformed;
  out["torn_bytes"] = in.counts().torn_bytes;
  return out;
}

// `afford experiment` in this process: (exit code, the signal that stopped it or 0, the last errors said).
// The GIL is released while it runs; SIGINT (a notebook's interrupt) stops
// it as it stops the command, and Python's own handlers are put back after.
py::tuple runExperimentFrom(const py::dict& request) {
  ExperimentRequest o;
  o.plan.experiment = request["experiment"].cast<std::string>();
  o.plan.systems = parseSystems(request["systems"].cast<std::vector<std::string>>(), "system");
  if (!request["reps"].is_none()) o.plan.reps = request["reps"].cast<int>();
  if (!request["steps"].is_none()) o.plan.steps = request["steps"].cast<std::int64_t>();
  o.plan.seed = request["seed"].cast<std::int64_t>();
  if (!request["tables"].is_none()) o.plan.tables = request["tables"].cast<int>();
  if (!request["table_seed"].is_none()) o.plan.table_seed = request["table_seed"].cast<std::int64_t>();
  o.host.jobs = request["jobs"].cast<int>();
  o.write.out_dir = request["out"].cast<std::string>();
  o.plan.log_root = request["log_root"].cast<std::string>();
  o.host.transport = request["transport"].cast<std::string>();
  o.plan.keep_logs = request["keep_logs"].cast<std::string>();
  o.plan.settings = request["settings"].cast<std::vector<std::string>>();
  o.plan.extrinsic_reps = request["extrinsic_reps"].cast<int>();
  o.plan.scenarios = request["scenarios"].cast<std::vector<std::string>>();
  o.plan.run_prefix = request["run_prefix"].cast<std::string>();
  o.host.progress = request["progress"].cast<std::string>();
  o.host.reuse_agents = request["reuse_agents"].cast<bool>();
  o.host.processes = parseProcessSwaps(
      [&] {
        std::vector<std::string> swaps;
        for (const auto& [name, command] : request["processes"].cast<std::map<std::string, std::string>>())
          swaps.push_back(name + "=" + command);
        return swaps;
      }(),
      "processes");
  o.write.quiet = true;
  o.write.replace = request["replace"].cast<bool>();
  o.write.program = "python3 -c 'import afford; afford.run(...)'; or: build/bin/afford";
  // Said on stderr at the level asked; the errors also kept (the last 20), for the exception that says why.
  const spdlog::level::level_enum level = parseLevel(request["log_level"].cast<std::string>());
  auto console = std::make_shared<spdlog::sinks::stderr_color_sink_mt>();
  console->set_level(level);
  auto errors = std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(20);
  errors->set_level(spdlog::level::err);
  auto log = std::make_shared<spdlog::logger>("afford", spdlog::sinks_init_list{console, errors});
  log->set_level(std::min(level, spdlog::level::err));
  log->set_pattern("[%H:%M:%S.%e] [%n] [%^%l%$] %v");
  errors->set_pattern("%v");
  int code = 0, signal = 0;
  {
    py::gil_scoped_release free;
    InterruptScope scope;
    code = runExperiment(o, *log);
    signal = scope.signal();
  }
  return py::make_tuple(code, signal, errors->last_formatted());
}



// ---- the environment and the eye in process, step by step (afford.env) ------------------

py::array_t<std::uint8_t> bytesImage(const std::uint8_t* data, int height, int width) {
  py::array_t<std::uint8_t> out({static_cast<py::ssize_t>(height), static_cast<py::ssize_t>(width),
                                 static_cast<py::ssize_t>(3)});
  std::memcpy(out.mutable_data(), data, static_cast<std::size_t>(height) * width * 3);
  return out;
}

// The environment core and the eye core of one run, driven a step at a time:
// the eye's bottom-up scan (or a look where the caller says) picks the object,
// the action is executed on it, the eye sees its effect, and the next step's
// scan follows, as in the agent's loop (paper Algorithm 1) without predictors.
class World {
 public:
  World(const std::string& experiment, const std::string& system, std::int64_t seed,
        const std::vector<std::string>& settings, const std::string& scenario)
      : config_(parseRunConfig(effectiveConfig(defaultConfigDir(),
                                               RunRequest{experiment, parseSystem(system), seed, std::nullopt,
                                                          settings}))) {
    if (!scenario.empty()) scenario_ = loadScenario(defaultConfigDir(), scenario, config_.world);
    reset();
  }

  void reset() {
    env_ = scenario_ ? std::make_unique<Environment>(config_, *scenario_) : std::make_unique<Environment>(config_);
    eye_ = std::make_unique<Eye>(config_);
    step_ = 0;
    eye_->setScene(env_->render(), env_->centres());
    if (scenario_) eye_->setGoal(env_->goalScene(), env_->goalCentres());
    eye_->scan(step_);
  }

  py::dict observation() const {
    py::dict o;
    const cv::Mat& scene = eye_->scene();
    o["scene"] = bytesImage(scene.data, scene.rows, scene.cols);
    const Focus& f = eye_->focus();
    const int side = focusSide(f);
    o["focus"] = bytesImage(f.image.data(), side, side);
    o["gaze"] = py::array_t<double>(2, std::array<double, 2>{f.x, f.y}.data());
    return o;
  }

  // Look at (x, y) first when x >= 0 (else at what the scan found), then do `act` (0-3; 4 passes).
  py::dict step(int act, double x, double y) {
    if (act < 0 || act > kNumActions)
      throw std::invalid_argument("action " + std::to_string(act) + ": 0-3 (move, turn green, turn red, turn blue) "
                                  "or 4 (pass)");
    if (x >= 0 && y >= 0) eye_->lookAt(std::min(x, 1.0), std::min(y, 1.0));
    const Focus f = eye_->focus();
    py::dict info;
    info["step"] = step_;
    info["acted"] = act < kNumActions;
    info["on_object"] = false;
    info["succeeded"] = false;
    info["image_changed"] = false;
    info["position_changed"] = false;
    if (act < kNumActions) {
      const ActionOutcome out = env_->execute(step_, act, f.x, f.y);
      info["on_object"] = out.on_object;
      info["succeeded"] = out.succeeded;
      const Effect e = eye_->scanEffect(step_, env_->render(), act, env_->centres());
      info["image_changed"] = e.image_changed;
      info["position_changed"] = e.position_changed;
    }
    ++step_;
    if (env_->introduceObjectsAt(step_)) eye_->setScene(env_->render(), env_->centres());
    eye_->scan(step_);
    info["goal_distance"] = scenario_ ? env_->goalDistance() : -1.0;
    return info;
  }

  std::int64_t stepCount() const { return step_; }
  std::int64_t steps() const { return config_.steps; }
  int sceneSize() const { return config_.world.size_px; }
  int focusSide() const { return focusSide(eye_->focus()); }
  double successDistance() const { return config_.planner.success_distance; }
  py::array_t<std::uint8_t> goal() const {
    if (!scenario_) throw std::runtime_error("this world has no scenario: no goal image");
    const cv::Mat& g = env_->goalScene();
    return bytesImage(g.data, g.rows, g.cols);
  }

 private:
  static int focusSide(const Focus& f) {
    int side = 0;
    while ((side + 1) * (side + 1) * 3 <= static_cast<int>(f.image.size())) ++side;
    return side;
  }

  RunConfig config_;
  std::optional<Scenario> scenario_;
  std::unique_ptr<Environment> env_;
  std::unique_ptr<Eye> eye_;
  std::int64_t step_ = 0;
};

}  // namespace
}  // namespace afford

PYBIND11_MODULE(_afford, m) {
  // The executables this module was built with (afford-<name> for udpm runs): $AFFORD_BIN, or the build's.
  const char* bin = std::getenv("AFFORD_BIN");
  afford::setExecutableDir(bin && *bin ? bin : AFFORD_BIN_DIR);
  m.doc() = "afford's C++ core for the Python package: the log reader, the message types";
  py::register_exception<afford::ConfigError>(m, "ConfigError", PyExc_ValueError);
  m.def("read_log", &afford::readLog, py::arg("path"), py::arg("run_id") = "", py::arg("bus_key") = "",
        py::arg("channels") = std::vector<std::string>{},
        "The messages of one run of a log folder (or .lcm file), read and checked by the project's reader.");
  m.def("run_experiment", &afford::runExperimentFrom, py::arg("request"),
        "Run an experiment in this process (afford experiment); returns (exit code, signal or 0, the last errors).");
  m.def("channels", [] { return afford::channelNames(); }, "Every channel of the protocol, in the protocol's order.");
  afford::defineComponents(m);
  py::class_<afford::World>(m, "World", "The environment and the eye of one run, a step at a time (afford.env).")
      .def(py::init<const std::string&, const std::string&, std::int64_t, const std::vector<std::string>&,
                    const std::string&>(),
           py::arg("experiment"), py::arg("system"), py::arg("seed"), py::arg("settings"), py::arg("scenario"))
      .def("reset", &afford::World::reset)
      .def("observation", &afford::World::observation)
      .def("step", &afford::World::step, py::arg("act"), py::arg("x") = -1.0, py::arg("y") = -1.0)
      .def_property_readonly("step_count", &afford::World::stepCount)
      .def_property_readonly("steps", &afford::World::steps)
      .def_property_readonly("scene_size", &afford::World::sceneSize)
      .def_property_readonly("focus_side", py::overload_cast<>(&afford::World::focusSide, py::const_))
      .def_property_readonly("success_distance", &afford::World::successDistance)
      .def("goal", &afford::World::goal);
  m.attr("version") = afford::affordVersion();
}
