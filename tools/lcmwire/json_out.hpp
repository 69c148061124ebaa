// afford-lcmwire's JSON output (json_out.cpp): for every type, its JSON Schema
// and its conversion of a decoded message to JSON (afford export,
// experiment/export). A host tool of the build: the standard library only.
#pragma once
#include <ostream>
#include <string>
#include <vector>

#include "lcm_types.hpp"

namespace lcmwire {

// Writes afford/json_messages.hpp: `order` has parts before the types that hold them.
void writeJsonMessages(std::ostream& o, const std::vector<const Struct*>& order, const std::vector<std::string>& files);

}  // namespace lcmwire
