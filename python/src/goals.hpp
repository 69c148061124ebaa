// A goal chooser written in Python, registered for goals.kind (python/src/goals.cpp).
#pragma once
#include <pybind11/pybind11.h>

#include <functional>
#include <string>

#include "motivation/goals.hpp"

namespace afford {

// Make `cls` (constructed with config(params): the run's configuration as a dict) the goal chooser of `kind`.
void registerPythonGoals(const std::string& kind, pybind11::object cls,
                         std::function<pybind11::dict(const GoalParams&)> config);

}  // namespace afford
