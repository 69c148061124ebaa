#include "environment/world.hpp"

#include "environment/table_world.hpp"

namespace afford {

std::unique_ptr<SimWorld> makeWorld(const RunConfig& config) {
  if (config.world.kind == WorldKind::Table) return std::make_unique<TableWorld>(config);
  if (config.phase != Phase::Extrinsic) return std::make_unique<Environment>(config);
  if (!config.scenario)
    throw ConfigError("extrinsic.scenario: missing (an extrinsic run needs a scenario)", "extrinsic.scenario");
  return std::make_unique<Environment>(config, *config.scenario);
}

}  // namespace afford
