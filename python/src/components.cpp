#include "components.hpp"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "afford/config.hpp"
#include "afford/node.hpp"
#include "afford/process_main.hpp"
#include "afford/rng.hpp"
#include "goals.hpp"
#include "motivation/component.hpp"
#include "motivation/node.hpp"
#include "predictors/affordance.hpp"
#include "predictors/node.hpp"

namespace py = pybind11;

namespace afford {
namespace {

// A YAML node as Python values: maps as dicts, lists as lists, scalars as
// bool, int, float or str (in that order of trial), null as None.
py::object fromYaml(const YAML::Node& n) {
  if (n.IsMap()) {
    py::dict d;
    for (const auto& kv : n) d[py::str(kv.first.Scalar())] = fromYaml(kv.second);
    return std::move(d);
  }
  if (n.IsSequence()) {
    py::list l;
    for (const auto& v : n) l.append(fromYaml(v));
    return std::move(l);
  }
  if (!n.IsScalar()) return py::none();
  const std::string& s = n.Scalar();
  if (n.Tag() != "!") {  // not quoted
    if (s == "true") return py::bool_(true);
    if (s == "false") return py::bool_(false);
    std::int64_t i = 0;
    if (YAML::convert<std::int64_t>::decode(n, i) && s.find_first_of(".eE") == std::string::npos) return py::int_(i);
    double x = 0;
    if (YAML::convert<double>::decode(n, x)) return py::float_(x);
  }
  return py::str(s);
}

// The run's configuration as a component's constructor gets it: the run's
// whole configuration (its RUN_CONFIG) as nested dicts, config["motivation"]
// ["leak"], with `steps` and `motivation_kind` at the top for convenience.
struct Configured {
  const std::string& text;
  const std::string& experiment;
  System system;
  std::int64_t seed, steps;
  const std::string& motivation_kind;
};
Configured configured(const MotivationParams& p) {
  return {p.config_text, p.experiment, p.system, p.seed, p.steps, p.motivation.kind};
}
Configured configured(const AffordanceParams& p) {
  return {p.config_text, p.experiment, p.system, p.seed, p.steps, p.motivation_kind};
}
py::dict configDict(const Configured& c) {
  py::dict d;
  if (!c.text.empty()) d = fromYaml(YAML::Load(c.text));
  d["experiment"] = c.experiment;
  d["system"] = toString(c.system);
  d["seed"] = c.seed;
  d["steps"] = c.steps;
  d["motivation_kind"] = c.motivation_kind;
  return d;
}

// A Python object's attribute, or a dict's entry of that name.
py::object field(const py::object& r, const char* name) {
  if (py::isinstance<py::dict>(r)) return py::object(r.cast<py::dict>()[name]);
  return py::getattr(r, name);
}

// The Python object that stands in for a component: constructed with the
// run's configuration; each call holds the GIL; a Python exception becomes
// the run's failure, naming the role, the kind and the Python error.
class PythonObject {
 public:
  PythonObject(std::string role, std::string kind, const py::object& cls, const Configured& config)
      : role_(std::move(role)), kind_(std::move(kind)) {
    py::gil_scoped_acquire gil;
    try {
      obj_ = cls(configDict(config));
    } catch (py::error_already_set& e) {
      throw ConfigError(what() + ": its constructor failed: " + e.what());
    }
  }
  ~PythonObject() {
    py::gil_scoped_acquire gil;
    obj_ = py::object();
  }
  PythonObject(const PythonObject&) = delete;
  PythonObject& operator=(const PythonObject&) = delete;

  // "motivation 'kind' (Python)"
  std::string what() const { return role_ + " '" + kind_ + "' (Python)"; }
  const py::object& obj() const { return obj_; }
  bool flag(const char* name) const {
    py::gil_scoped_acquire gil;
    return py::bool_(py::getattr(obj_, name, py::bool_(false)));
  }

 private:
  std::string role_, kind_;
  py::object obj_;
};

// ---- the motivation ---------------------------------------------------------------------

// What decide() must return, said with what it returned instead.
constexpr const char* kDecideReturns =
    "decide() returns an afford.Decision(act, action, motivation, threshold), or a dict or an object with those "
    "four: act a bool, action 0..3 when acting, motivation and threshold numbers";

// decide()'s answer as a Decision; anything else is refused naming what came and what is expected.
Decision decisionOf(const py::object& r, const std::string& at) {
  const std::string type = py::str(py::type::of(r).attr("__name__")).cast<std::string>();
  const bool mapping = py::isinstance<py::dict>(r);
  if (r.is_none() || py::isinstance<py::tuple>(r) || py::isinstance<py::list>(r) || py::isinstance<py::str>(r) ||
      py::isinstance<py::bool_>(r) || py::isinstance<py::int_>(r) || py::isinstance<py::float_>(r))
    throw std::runtime_error(at + " returned " + (r.is_none() ? std::string("None") : "a " + type) + ": " +
                             kDecideReturns);
  const auto get = [&](const char* name, bool needed) -> py::object {
    if (mapping ? r.cast<py::dict>().contains(name) : py::hasattr(r, name)) return field(r, name);
    if (!needed) return py::none();
    throw std::runtime_error(at + " returned a " + type + " without '" + name + "': " + kDecideReturns);
  };
  const auto number = [&](const char* name, py::object v, auto as) {
    try {
      return v.cast<decltype(as)>();
    } catch (py::cast_error&) {
      throw std::runtime_error(at + " returned " + name + " = " + py::repr(v).cast<std::string>() + ": " +
                               kDecideReturns);
    }
  };
  Decision d;
  const py::object act = get("act", true);
  if (!py::isinstance<py::bool_>(act) && !py::isinstance<py::int_>(act) &&
      !py::hasattr(act, "__bool__"))  // numpy's bool_ has __bool__
    throw std::runtime_error(at + " returned act = " + py::repr(act).cast<std::string>() + ": " + kDecideReturns);
  d.act = py::bool_(act);
  d.action = d.act ? number("action", get("action", true), int{}) : -1;
  if (d.act && (d.action < 0 || d.action >= kNumActions))
    throw std::runtime_error(at + " returned action " + std::to_string(d.action) + ", not one of 0.." +
                             std::to_string(kNumActions - 1));
  d.motivation = number("motivation", get("motivation", true), double{});
  d.threshold = number("threshold", get("threshold", true), double{});
  return d;
}

class PythonMotivation : public MotivationComponent {
 public:
  PythonMotivation(const std::string& kind, const py::object& cls, const MotivationParams& params)
      : py_("motivation", kind, cls, configured(params)) {}

  Decision decide(const Percept& p) override {
    py::gil_scoped_acquire gil;
    const std::string at = py_.what() + ": decide() at step " + std::to_string(p.step);
    try {
      py::dict percept;
      percept["step"] = p.step;
      percept["affordance"] = py::array_t<double>(kNumActions, p.affordance.data());
      percept["learning_progress"] = py::array_t<double>(kNumActions, p.learning_progress.data());
      percept["look"] = p.look;
      percept["tried_ago"] = p.tried_ago ? py::object(py::array_t<std::int64_t>(kNumActions, p.tried_ago->data()))
                                         : py::object(py::none());
      percept["last_change"] = p.last_change ? py::object(py::float_(*p.last_change)) : py::object(py::none());
      return decisionOf(py_.obj().attr("decide")(percept), at);
    } catch (py::error_already_set& e) {
      throw std::runtime_error(at + " raised " + e.what());
    }
  }
  // Asked before each step: a motivation may need the report only after some steps (IMP's observed change).
  bool needsMemory() const override { return py_.flag("needs_memory"); }
  bool needsLastChange() const override { return py_.flag("needs_last_change"); }

 private:
  PythonObject py_;
};

// ---- the affordance predictor -------------------------------------------------------------

// Four numbers from a Python sequence, or an error naming what gave them.
PerAction perAction(const py::handle& v, const std::string& what) {
  std::vector<double> xs;
  try {
    xs = v.cast<std::vector<double>>();
  } catch (py::cast_error&) {
    throw std::runtime_error(what + " is not a sequence of numbers");
  }
  if (xs.size() != kNumActions)
    throw std::runtime_error(what + " has " + std::to_string(xs.size()) + " numbers, not one per action (" +
                             std::to_string(kNumActions) + ")");
  for (std::size_t a = 0; a < xs.size(); ++a)
    if (!std::isfinite(xs[a])) throw std::runtime_error(what + "[" + std::to_string(a) + "] is not finite");
  PerAction out{};
  std::copy(xs.begin(), xs.end(), out.begin());
  return out;
}

class PythonAffordance : public AffordanceComponent {
 public:
  PythonAffordance(const std::string& kind, const py::object& cls, const AffordanceParams& params)
      : py_("affordance predictor", kind, cls, configured(params)), side_(params.focus_side) {
    for (int a = 0; a < kNumActions; ++a) state(a);  // a state the checksum cannot take is refused at once
  }

  void predict(const FocusView& focus, PerAction& affordance, PerAction& learning_progress) const override {
    py::gil_scoped_acquire gil;
    const std::string at = py_.what() + ": predict()";
    try {
      const py::object r = py_.obj().attr("predict")(image(focus));
      const py::tuple t = r.cast<py::tuple>();
      if (t.size() != 2) throw py::cast_error("not a pair");
      affordance = perAction(t[0], at + "'s affordance");
      learning_progress = perAction(t[1], at + "'s learning progress");
    } catch (py::error_already_set& e) {
      throw std::runtime_error(at + " raised " + e.what());
    } catch (py::cast_error&) {
      throw std::runtime_error(at + " returned no pair (affordance, learning_progress)");
    }
  }

  Learned learn(const FocusView& focus, int action, bool succeeded) override {
    py::gil_scoped_acquire gil;
    const std::string at = py_.what() + ": learn()";
    try {
      const py::object r = py_.obj().attr("learn")(image(focus), action, succeeded);
      Learned l;
      if (py::isinstance<py::tuple>(r) && r.cast<py::tuple>().size() == 3) {
        const py::tuple t = r.cast<py::tuple>();
        l.before = t[0].cast<double>();
        l.after = t[1].cast<double>();
        l.learning_progress = t[2].cast<double>();
      } else {
        l.before = field(r, "before").cast<double>();
        l.after = field(r, "after").cast<double>();
        l.learning_progress = field(r, "learning_progress").cast<double>();
      }
      if (!std::isfinite(l.before) || !std::isfinite(l.after) || !std::isfinite(l.learning_progress))
        throw std::runtime_error(at + " returned a number that is not finite (before " + std::to_string(l.before) +
                                 ", after " + std::to_string(l.after) + ", learning progress " +
                                 std::to_string(l.learning_progress) + ")");
      return l;
    } catch (py::error_already_set& e) {
      throw std::runtime_error(at + " raised " + e.what());
    } catch (py::cast_error&) {
      throw std::runtime_error(at + " returned no (before, after, learning_progress)");
    }
  }

  void relearn(const FocusView& focus, int action, bool succeeded) override {
    py::gil_scoped_acquire gil;
    try {
      py_.obj().attr("relearn")(image(focus), action, succeeded);
    } catch (py::error_already_set& e) {
      throw std::runtime_error(py_.what() + ": relearn() raised " + e.what());
    }
  }

  std::vector<StateArray> state(int action) override {
    py::gil_scoped_acquire gil;
    const std::string at = py_.what() + ": state(" + std::to_string(action) + ")";
    py::list arrays;
    try {
      arrays = py::list(py_.obj().attr("state")(action));
    } catch (py::error_already_set& e) {
      throw std::runtime_error(at + " raised " + e.what());
    }
    if (action == 0) held_.clear();  // the arrays stay referenced until the next pass over the state
    std::vector<StateArray> out;
    for (std::size_t i = 0; i < arrays.size(); ++i) {
      const py::handle a = arrays[i];
      const std::string which = at + "[" + std::to_string(i) + "]";
      if (!py::isinstance<py::array>(a)) throw std::runtime_error(which + " is not a numpy array of float64");
      auto arr = py::reinterpret_borrow<py::array>(a);
      if (arr.dtype().kind() != 'f' || arr.itemsize() != sizeof(double))
        throw std::runtime_error(which + " is an array of " + std::string(py::str(arr.dtype())) + ", not float64");
      if (!(arr.flags() & py::array::c_style) || !arr.writeable())
        throw std::runtime_error(which + " is not a contiguous, writeable array (the checkpoint is loaded into it)");
      out.push_back({static_cast<double*>(arr.mutable_data()), static_cast<std::size_t>(arr.size())});
      held_.push_back(std::move(arr));
    }
    return out;
  }

  ~PythonAffordance() override {
    py::gil_scoped_acquire gil;
    held_.clear();
  }

 private:
  py::array_t<std::uint8_t> image(const FocusView& f) const {
    if (f.image.size() != static_cast<std::size_t>(side_) * side_ * 3)
      throw std::runtime_error(py_.what() + ": a focus image of " + std::to_string(f.image.size()) + " bytes, not " +
                               std::to_string(side_) + " x " + std::to_string(side_) + " x 3");
    py::array_t<std::uint8_t> out({side_, side_, static_cast<py::ssize_t>(3)});
    std::memcpy(out.mutable_data(), f.image.data(), f.image.size());
    return out;
  }

  PythonObject py_;
  py::ssize_t side_;
  std::vector<py::array> held_;
};

// A process of the bus (`python3 -m afford.process NAME MODULE:CLASS ARGS`), its
// component the Python class registered first. ARGS: a process's standard ones.
int serve(const std::string& name, const std::vector<std::string>& args) {
  std::vector<std::string> owned = args;
  std::vector<char*> argv;
  for (std::string& a : owned) argv.push_back(a.data());
  argv.push_back(nullptr);
  const int argc = static_cast<int>(owned.size());
  py::gil_scoped_release free;
  if (name == "motivation" || name == "goals")  // a goal chooser is the motivation process's, in the goals phase
    return processMain(argc, argv.data(),
                       {"motivation",
                        name == "goals" ? "a goal chooser written in Python (afford.process)"
                                        : "a motivation written in Python (afford.process)",
                        /*fork_snapshots=*/false},
                       [](CLIHook&) {},
                       [](lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol) {
                         return std::make_unique<MotivationNode>(lcm, std::move(log), protocol);
                       });
  if (name == "predictors") {
    std::string checkpoint_root = "logs";
    return processMain(
        argc, argv.data(), {"predictors", "predictors with an affordance predictor written in Python (afford.process)",
         /*fork_snapshots=*/false},
        [&](CLIHook& cli) {
          cli.option("--checkpoint-dir", checkpoint_root,
                     "the only folder checkpoints are written in (<dir>/<run-id>/) and read from");
        },
        [&](lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol) {
          return std::make_unique<PredictorsNode>(lcm, std::move(log), protocol, /*async_effects=*/true,
                                                  checkpoint_root);
        });
  }
  throw std::invalid_argument("'" + name +
                              "': a component in Python stands in for the motivation, the goal chooser (goals) or the "
                              "predictors");
}

Purpose purposeNamed(const std::string& name) {
  if (name == "component") return Purpose::Component;
  if (name == "learning_progress_init") return Purpose::LearningProgressInit;
  if (name == "replay") return Purpose::Replay;
  if (name == "revisit") return Purpose::Revisit;
  if (name == "goal_choice") return Purpose::GoalChoice;
  throw std::invalid_argument("purpose '" + name + "': component, or to port a shipped component, "
                              "learning_progress_init, replay, revisit or goal_choice");
}

}  // namespace

void defineComponents(py::module_& m) {
  m.def(
      "register_motivation",
      [](const std::string& kind, py::object cls) {
        auto shared = std::make_shared<py::object>(std::move(cls));
        registerMotivation(kind, [kind, shared](const MotivationParams& p) {
          return std::make_unique<PythonMotivation>(kind, *shared, p);
        });
      },
      py::arg("kind"), py::arg("cls"),
      "Make cls (constructed with the run's configuration, with decide(percept)) the motivation of that kind.");
  m.def(
      "register_affordance",
      [](const std::string& kind, py::object cls) {
        auto shared = std::make_shared<py::object>(std::move(cls));
        registerAffordance(kind, [kind, shared](const AffordanceParams& p) {
          return std::make_unique<PythonAffordance>(kind, *shared, p);
        });
      },
      py::arg("kind"), py::arg("cls"),
      "Make cls (with predict, learn, relearn and state) the affordance predictor of that kind.");
  m.def(
      "register_goals",
      [](const std::string& kind, py::object cls) {
        registerPythonGoals(kind, std::move(cls), [kind](const GoalParams& p) {
          return configDict(Configured{p.config_text, p.experiment, p.system, p.seed, p.steps, kind});
        });
      },
      py::arg("kind"), py::arg("cls"),
      "Make cls (constructed with the run's configuration, with next(step, id)) the goal chooser of that kind.");
  m.def("goal_chooser_kinds", &goalChooserKinds, "The goal chooser kinds of this process.");
  m.def("motivation_kinds", &motivationKinds, "The motivation kinds of this process.");
  m.def("affordance_kinds", &affordanceKinds, "The affordance predictor kinds of this process.");
  m.def("serve", &serve, py::arg("name"), py::arg("argv"),
        "Run the process `name` (motivation or predictors), its standard arguments in argv (argv[0] its name).");
  py::class_<KeyedRng>(m, "KeyedRng", "The run's keyed generator: (seed, step, purpose, sub).")
      .def(py::init([](std::int64_t seed, std::int64_t step, std::uint64_t sub, const std::string& purpose) {
             return KeyedRng(seed, step, purposeNamed(purpose), sub);
           }),
           py::arg("seed"), py::arg("step"), py::arg("sub"), py::arg("purpose") = "component")
      .def("bits", &KeyedRng::bits, py::arg("i") = 0, "The i-th 64-bit draw.")
      .def("uniform", py::overload_cast<std::uint64_t>(&KeyedRng::uniform, py::const_), py::arg("i") = 0,
           "The i-th draw, uniform in [0, 1).");
}

}  // namespace afford
