// A goal chooser written in Python (docs/writing-a-component.md#goal-choosers):
// a class with next(step, id) and, if it wants them, saw_object, saw_effect,
// imagined and attempted, in the place of goals.kind's C++ chooser.
#include "goals.hpp"

#include <pybind11/numpy.h>

#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "afford/actions.hpp"
#include "motivation/goals.hpp"

namespace py = pybind11;

namespace afford {

namespace {

// What next() returns, said with what it returned instead.
constexpr const char* kNextReturns =
    "next() returns an afford.Goal, or a dict or an object with module ('explore', 'colour', 'move', "
    "'colour_place' or 0..3), and for explore an action 0..3, for the others object_x, object_y, x, y in [0, 1] and "
    "image, the focus image wanted at (x, y) (side x side x 3 uint8)";

py::object part(const py::object& r, const char* name) {
  if (py::isinstance<py::dict>(r)) {
    const auto d = r.cast<py::dict>();
    return d.contains(name) ? py::object(d[name]) : py::object(py::none());
  }
  return py::getattr(r, name, py::none());
}

class PythonGoals : public GoalChooser {
 public:
  PythonGoals(std::string kind, const py::object& cls, const GoalParams& p, py::dict config)
      : kind_(std::move(kind)), side_(p.focus_side) {
    py::gil_scoped_acquire gil;
    try {
      obj_ = cls(std::move(config));
    } catch (py::error_already_set& e) {
      throw ConfigError(what() + ": its constructor failed: " + e.what());
    }
  }
  ~PythonGoals() override {
    py::gil_scoped_acquire gil;
    obj_ = py::object();
  }

  void sawObject(std::int64_t step, const Seen& o) override {
    call("saw_object", [&] { return std::make_tuple(step, image(o.image), o.x, o.y); });
  }
  void sawEffect(const SeenEffect& e) override {
    call("saw_effect", [&] {
      py::dict d;
      d["step"] = e.step;
      d["action"] = e.action;
      d["before_image"] = image(e.before.image);
      d["before"] = py::make_tuple(e.before.x, e.before.y);
      d["after_image"] = image(e.after.image);
      d["after"] = py::make_tuple(e.after.x, e.after.y);
      d["target"] = py::make_tuple(e.target_x, e.target_y);
      d["affordance"] = e.affordance;
      return std::make_tuple(d);
    });
  }
  void imagined(const Imagined& o) override {
    call("imagined", [&] {
      py::dict d;
      d["step"] = o.step;
      d["action"] = o.action;
      d["object_image"] = image(o.object);
      d["image"] = image(o.image);
      d["place"] = py::make_tuple(o.x, o.y);
      return std::make_tuple(d);
    });
  }
  void attempted(const GoalAttempt& a) override {
    call("attempted", [&] {
      py::dict d;
      d["id"] = a.id;
      d["module"] = kGoalModuleNames[static_cast<std::size_t>(a.module)];
      d["reached"] = a.reached;
      d["distance"] = a.distance;
      d["actions"] = a.actions;
      return std::make_tuple(d);
    });
  }

  Goal next(std::int64_t step, int id) override {
    py::gil_scoped_acquire gil;
    const std::string at = what() + ": next() at step " + std::to_string(step) + " (goal " + std::to_string(id) + ")";
    py::object r;
    try {
      r = obj_.attr("next")(step, id);
    } catch (py::error_already_set& e) {
      throw std::runtime_error(at + " raised " + e.what());
    }
    return goalOf(r, at);
  }

 private:
  std::string what() const { return "goal chooser '" + kind_ + "' (Python)"; }

  py::array_t<std::uint8_t> image(const std::vector<std::uint8_t>& bytes) const {
    py::array_t<std::uint8_t> out({static_cast<py::ssize_t>(side_), static_cast<py::ssize_t>(side_), py::ssize_t{3}});
    if (bytes.size() == static_cast<std::size_t>(out.size())) std::memcpy(out.mutable_data(), bytes.data(), bytes.size());
    return out;
  }

  // An optional method, called with the GIL held; a Python exception fails the run, naming it.
  template <class Args>
  void call(const char* method, Args args) {
    py::gil_scoped_acquire gil;
    if (!py::hasattr(obj_, method)) return;
    try {
      std::apply([&](auto&&... a) { obj_.attr(method)(a...); }, args());
    } catch (py::error_already_set& e) {
      throw std::runtime_error(what() + ": " + method + "() raised " + e.what());
    }
  }

  Goal goalOf(const py::object& r, const std::string& at) const {
    const auto refuse = [&](const std::string& why) { return std::runtime_error(at + " returned " + why + ": " + kNextReturns); };
    if (r.is_none() || py::isinstance<py::str>(r) || py::isinstance<py::int_>(r) || py::isinstance<py::float_>(r))
      throw refuse(py::repr(r).cast<std::string>());
    Goal g;
    const py::object module = part(r, "module");
    int m = -1;
    if (py::isinstance<py::str>(module)) {
      const auto name = module.cast<std::string>();
      for (int i = 0; i < kGoalModules; ++i)
        if (name == kGoalModuleNames[static_cast<std::size_t>(i)]) m = i;
    } else if (py::isinstance<py::int_>(module)) {
      m = module.cast<int>();
    }
    if (m < 0 || m >= kGoalModules) throw refuse("module = " + py::repr(module).cast<std::string>());
    g.module = static_cast<GoalModule>(m);
    const auto number = [&](const char* name, double lo, double hi) {
      const py::object v = part(r, name);
      double x = 0;
      try {
        x = v.cast<double>();
      } catch (py::cast_error&) {
        throw refuse(std::string(name) + " = " + py::repr(v).cast<std::string>());
      }
      if (!(x >= lo && x <= hi)) throw refuse(std::string(name) + " = " + std::to_string(x) + ", outside its range");
      return x;
    };
    if (g.module == GoalModule::Explore) {
      g.action = static_cast<int>(number("action", 0, kNumActions - 1));
      return g;
    }
    g.object_x = number("object_x", 0, 1);
    g.object_y = number("object_y", 0, 1);
    g.x = number("x", 0, 1);
    g.y = number("y", 0, 1);
    const py::object img = part(r, "image");
    py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast> a;
    try {
      a = img.cast<py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>>();
    } catch (py::cast_error&) {
      throw refuse("image = " + py::repr(img).cast<std::string>());
    }
    const auto want = static_cast<py::ssize_t>(side_) * side_ * 3;
    if (a.size() != want)
      throw refuse("an image of " + std::to_string(a.size()) + " values, not " + std::to_string(side_) + " x " +
                   std::to_string(side_) + " x 3");
    g.image.assign(a.data(), a.data() + a.size());
    return g;
  }

  std::string kind_;
  int side_;
  py::object obj_;
};

}  // namespace

void registerPythonGoals(const std::string& kind, py::object cls, std::function<py::dict(const GoalParams&)> config) {
  auto shared = std::make_shared<py::object>(std::move(cls));
  registerGoalChooser(kind, [kind, shared, config](const GoalParams& p) {
    py::gil_scoped_acquire gil;
    return std::make_unique<PythonGoals>(kind, *shared, p, config(p));
  });
}

}  // namespace afford
