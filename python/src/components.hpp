// Components written in Python (docs/python.md#components-in-python): a
// Python class in the place of a C++ component (the motivation, the
// affordance predictor), in this process or as a process on the bus whose
// node and edge are the C++ ones.
#pragma once
#include <pybind11/pybind11.h>

namespace afford {

// register_motivation, register_affordance, serve, KeyedRng, ... on the module.
void defineComponents(pybind11::module_& m);

}  // namespace afford
