// afford._afford: the project's C++ behind the Python package (python/afford).
// No protocol or file format is written again in Python: a log is read by the
// project's log reader and each message decoded and checked by the edge's
// decodeChecked, then converted by the conversions afford-lcmwire generates
// from the .lcm files (afford/to_python.hpp).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <spdlog/pattern_formatter.h>
#include <spdlog/sinks/sink.h>
#include <spdlog/sinks/null_sink.h>
#include <spdlog/sinks/ringbuffer_sink.h>
#include <spdlog/sinks/stdout_color_sinks.h>

#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
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
#include "viewer/step_order.hpp"
#include "afford/rng.hpp"
#include "environment/environment.hpp"
#include "eye/eye.hpp"
#include "components.hpp"
#include "worlds.hpp"
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
  // Streamed, in step order (viewer/step_order.hpp): what is held is what is kept (a log of gigabytes read for
  // one channel holds that channel), and the messages come in the same order however the log interleaves them.
  StepOrderedLog<RecordedLogStream, RunSelector> in(
      [&](spdlog::logger& l) { return std::make_unique<RecordedLogStream>(path, l, key.get()); },
      [&](spdlog::logger& l) { return std::make_unique<RunSelector>(run_id, path, l); },
      loadProtocol(defaultConfigDir()), *log);
  const RunSelector& select = in.selector();
  std::unique_ptr<RunConfig> config;
  BoundsContext ctx{nullptr, nullptr};
  py::list messages;
  std::int64_t refused = 0, unknown = 0;
  std::string first_refusal;
  LogEvent e;
  StepKey at;
  while (in.next(e, at)) {
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
  select.check(in.cut(), in.stream().counts().key);
  out["run_id"] = select.config().run_id;
  out["config_yaml"] = select.config().config_yaml;
  out["messages"] = messages;
  out["refused"] = refused;
  out["first_refusal"] = first_refusal;
  out["unknown_channels"] = unknown;
  out["malformed"] = in.stream().counts().malformed;
  out["torn_bytes"] = in.stream().counts().torn_bytes;
  out["cut"] = in.cut();
  return out;
}

// The afford command beside the executables this module runs ($AFFORD_BIN, or the build's), which the command
// that resumes an experiment started here names; "afford", to be found on PATH, where there is none.
std::string affordCommand() {
  const std::filesystem::path exe = std::filesystem::path(executableDir()) / "afford";
  return access(exe.c_str(), X_OK) == 0 ? std::filesystem::absolute(exe).lexically_normal().string() : "afford";
}

// `afford experiment` in this process: (exit code, the signal that stopped it or 0, the last errors said, the
// reason the program stopped it or "").
// The GIL is released while it runs; SIGINT (a notebook's interrupt) stops
// it as it stops the command, and Python's own handlers are put back after.
ExperimentRequest requestFrom(const py::dict& request) {
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
  if (request.contains("truth_dir") && !request["truth_dir"].is_none()) o.plan.truth_dir = request["truth_dir"].cast<std::string>();
  o.host.transport = request["transport"].cast<std::string>();
  o.plan.keep_logs = request["keep_logs"].cast<std::string>();
  o.plan.settings = request["settings"].cast<std::vector<std::string>>();
  if (!request["extrinsic_reps"].is_none()) o.plan.extrinsic_reps = request["extrinsic_reps"].cast<int>();
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
  o.write.program = affordCommand();
  return o;
}

// The checks `afford experiment` makes before anything runs (its options, config keys and values, the plan),
// with nothing written: a ConfigError names what is wrong. The request must give a run prefix. Returns the
// intrinsic runs planned: [(run id, system, steps)].
py::list checkExperimentFrom(const py::dict& request) {
  py::list out;
  for (const CheckedRun& r : checkExperiment(requestFrom(request))) out.append(py::make_tuple(r.run_id, r.system, r.steps));
  return out;
}

// Each line said, given to a Python function (afford.run: Python's sys.stderr, which a notebook shows where
// the process's own stderr is not), with the GIL, and no lock of the sink held meanwhile (a thread holding the
// GIL may be logging); what the function raises is dropped, never thrown into the runner's threads.
class PythonSink : public spdlog::sinks::sink {
 public:
  explicit PythonSink(py::object say) : say_(std::move(say)) {}
  ~PythonSink() override {
    py::gil_scoped_acquire gil;
    say_ = py::object();
  }
  void say(const std::string& line) {
    py::gil_scoped_acquire gil;
    try {
      say_(line);
    } catch (py::error_already_set& e) {
      e.discard_as_unraisable("afford.run's say");
    }
  }
  void log(const spdlog::details::log_msg& msg) override {
    std::string line;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      spdlog::memory_buf_t text;
      formatter_->format(msg, text);
      line = fmt::to_string(text);
    }
    while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.pop_back();
    say(line);
  }
  void flush() override {}
  void set_pattern(const std::string& pattern) override {
    set_formatter(std::make_unique<spdlog::pattern_formatter>(pattern));
  }
  void set_formatter(std::unique_ptr<spdlog::formatter> formatter) override {
    std::lock_guard<std::mutex> lock(mutex_);
    formatter_ = std::move(formatter);
  }

 private:
  py::object say_;
  std::mutex mutex_;
  std::unique_ptr<spdlog::formatter> formatter_ = std::make_unique<spdlog::pattern_formatter>();
};

py::tuple runExperimentFrom(const py::dict& request) {
  ExperimentRequest o = requestFrom(request);
  // Said at the level asked (on stderr, or to request["say"] and its progress lines too); the errors also kept
  // (the last 20), for the exception that says why.
  const spdlog::level::level_enum level = parseLevel(request["log_level"].cast<std::string>());
  spdlog::sink_ptr console;
  if (request.contains("say") && !request["say"].is_none()) {
    auto to_python = std::make_shared<PythonSink>(py::object(request["say"]));
    o.host.progress_to = [to_python](const std::string& line) { to_python->say(line); };
    console = to_python;
  } else {
    console = std::make_shared<spdlog::sinks::stderr_color_sink_mt>();
  }
  console->set_level(level);
  auto errors = std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(20);
  errors->set_level(spdlog::level::err);
  auto log = std::make_shared<spdlog::logger>("afford", spdlog::sinks_init_list{console, errors});
  log->set_level(std::min(level, spdlog::level::err));
  log->set_pattern("[%H:%M:%S.%e] [%n] [%^%l%$] %v");
  errors->set_pattern("%v");
  // on_curve(run_id, system, run, step, mae), told each point of each intrinsic run's curve from the slot's
  // thread: a string it returns stops the experiment for that reason; an exception it raises stops it too,
  // and is raised here once the runs have stopped. (`hook` keeps the callable alive until then.)
  const py::object hook = request.contains("on_curve") ? py::object(request["on_curve"]) : py::object(py::none());
  std::optional<py::error_already_set> raised;
  std::mutex raised_mutex;
  if (!hook.is_none()) {
    PyObject* fn = hook.ptr();
    o.host.on_curve = [fn, &raised, &raised_mutex](const CurvePoint& p) {
      py::gil_scoped_acquire gil;
      try {
        const py::object said = py::reinterpret_borrow<py::object>(fn)(p.run_id, p.system, p.run, p.step, p.mae);
        if (py::isinstance<py::str>(said) && !said.cast<std::string>().empty()) stopExperiment(said.cast<std::string>());
      } catch (py::error_already_set& e) {
        std::lock_guard<std::mutex> lock(raised_mutex);
        if (!raised) raised.emplace(std::move(e));
        stopExperiment("on_curve raised an exception");
      } catch (const std::exception& e) {  // (a result it returned that is not a string)
        stopExperiment(std::string("on_curve: ") + e.what());
      }
    };
  }
  int code = 0, signal = 0;
  std::string stopped_for;
  {
    py::gil_scoped_release free;
    InterruptScope scope;
    code = runExperiment(o, *log);
    stopped_for = scope.stoppedFor();
    signal = scope.restore();
  }
  if (raised) throw std::move(*raised);
  return py::make_tuple(code, signal, errors->last_formatted(), stopped_for);
}

// afford replay in this process, where components registered from Python are known (a run with a Python
// affordance predictor replays here, and not with the command). The GIL is released while it runs.
py::dict replayFrom(const std::string& log_dir, const std::vector<std::string>& into, const std::string& run_id,
                    const std::string& bus_key, const std::string& log_level) {
  ReplayOptions o;
  o.log_dir = log_dir, o.into = into, o.run_id = run_id, o.bus_key = bus_key;
  auto console = std::make_shared<spdlog::sinks::stderr_color_sink_mt>();
  auto log = std::make_shared<spdlog::logger>("replay", console);
  log->set_level(parseLevel(log_level));
  log->set_pattern("[%H:%M:%S.%e] [%n] [%^%l%$] %v");
  ReplayResult r;
  {
    py::gil_scoped_release free;
    r = replayRun(o, *log);
  }
  py::dict d;
  d["run_id"] = r.run_id;
  d["events"] = r.events;
  d["weights_checksum"] = r.weights_checksum;
  d["recorded_checksum"] = r.recorded_checksum;
  d["decisions"] = r.decisions, d["decisions_recorded"] = r.decisions_recorded;
  d["decisions_differing"] = r.decisions_differing;
  d["decider_skipped"] = r.decider_skipped;
  d["dropped"] = r.dropped;
  d["incomplete"] = r.incomplete;
  d["gaps"] = static_cast<py::ssize_t>(r.gaps.size());
  d["cut"] = r.cut;
  d["ok"] = r.ok();
  d["consistent"] = r.consistent();
  return d;
}

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
  m.def("check_experiment", &afford::checkExperimentFrom, py::arg("request"),
        "Check an experiment request as afford experiment does before it runs (nothing is written).");
  m.def("run_experiment", &afford::runExperimentFrom, py::arg("request"),
        "Run an experiment in this process (afford experiment); returns (exit code, signal or 0, the last errors).");
  m.def("replay", &afford::replayFrom, py::arg("log_dir"), py::arg("into") = std::vector<std::string>{},
        py::arg("run_id") = "", py::arg("bus_key") = "", py::arg("log_level") = "warning",
        "Replay a recorded run into fresh learning processes in this process (afford replay); a dict of results.");
  m.def("channels", [] { return afford::channelNames(); }, "Every channel of the protocol, in the protocol's order.");
  afford::defineComponents(m);
  afford::defineWorlds(m);
  m.attr("version") = afford::affordVersion();
  py::list systems;  // every system an experiment runs (afford.run's `system`)
  for (const auto& s : afford::kSystemNames) systems.append(s.name);
  m.attr("systems") = py::tuple(systems);
}
