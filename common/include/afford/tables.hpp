// Random affordance tables (issue 11's random-tables experiment): a world's
// objects given tables other than the paper's Table 1, to test whether an
// agent learns any table. Each entry is 0 or 1, and every row (an object's
// actions) and every column (an action over the objects) holds both values,
// so no object affords everything or nothing and no action is afforded by
// all objects or none.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "afford/actions.hpp"

namespace afford {

using AffordanceTable = std::vector<std::array<double, kNumActions>>;

// Table `index` of the series drawn from `seed`, for `objects` objects (at
// least 2). The draw is keyed by (seed, index, Purpose::RandomTable): the same
// arguments give the same table on every machine, and a table does not depend
// on how many others are drawn. Throws std::invalid_argument for fewer than 2 objects.
AffordanceTable randomTable(std::int64_t seed, std::int64_t index, std::size_t objects);

// Every row and every column holds both 0 and 1.
bool mixed(const AffordanceTable& table);

}  // namespace afford
