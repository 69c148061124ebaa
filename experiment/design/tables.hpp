// Random affordance tables (issue 11's random-tables experiment): a world's
// objects given tables other than the paper's Table 1, to test whether an
// agent learns any table. Each entry is 0 or 1, and every row (an object's
// actions) and every column (an action over the objects) holds both values,
// so no object affords everything or nothing and no action is afforded by
// all objects or none. Turning an object to its own colour is never
// afforded: it changes nothing the eye could see (paper, Figure 7: "an
// object of a color does not have the affordance to be turned to the same
// color ... as this involves no change").
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "afford/actions.hpp"
#include "afford/config.hpp"

namespace afford {

using AffordanceTable = std::vector<std::array<double, kNumActions>>;

// Table `index` of the series drawn from `seed`, for `objects` (their colours
// decide which entries are 0; at least 2 objects). The draw is keyed by
// (seed, index, Purpose::RandomTable): the same arguments give the same table
// on every machine, and a table does not depend on how many others are drawn.
// Throws std::invalid_argument for fewer than 2 objects, and
// std::runtime_error if no mixed table exists for them.
AffordanceTable randomTable(std::int64_t seed, std::int64_t index, const std::vector<ObjectSpec>& objects);

// Every row and every column holds both 0 and 1.
bool mixed(const AffordanceTable& table);

// The action that turns an object of colour `c` to its own colour.
int ownColourAction(Colour c);

// The objects (indices) whose look, once left, cannot come back: a colour
// change is afforded to it, and no chain of afforded colour changes of its
// shape leads back to its colour. Affordances follow the look (model.md), so
// after the first colour change of such an object, what was not tried on it
// can never be tried (docs/model.md#revisit).
std::vector<std::size_t> oneWayLooks(const AffordanceTable& table, const std::vector<ObjectSpec>& objects);

}  // namespace afford
