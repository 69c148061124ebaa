// The world a run's configuration asks for (world.kind), as the environment process and afford.env build it.
#pragma once
#include <memory>

#include "afford/config.hpp"
#include "environment/environment.hpp"

namespace afford {

// The paper's grid (Environment) or the physical table (TableWorld), in the run's phase: an extrinsic run's
// world starts in its scenario's initial scene (config.scenario), the goal image drawn. A table world makes an
// OpenGL context for the calling thread and must be used on it alone.
// Throws ConfigError naming the key when the configuration does not make a world (an extrinsic run without a
// scenario, objects that do not fit the region), std::runtime_error when the table has no OpenGL to be had.
std::unique_ptr<SimWorld> makeWorld(const RunConfig& config);

}  // namespace afford
