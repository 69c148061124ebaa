// afford.env's C++ core: the environment and the eye of a run, a step at a time, one world (World) or many
// stepped in one call with the GIL released (Worlds) (python/src/worlds.cpp).
#pragma once
#include <pybind11/pybind11.h>

namespace afford {

void defineWorlds(pybind11::module_& m);

}  // namespace afford
