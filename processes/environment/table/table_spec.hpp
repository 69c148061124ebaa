// The physical table world (world.kind: table): what a table, its camera, its hand and its objects are,
// as numbers a configuration gives. The model MuJoCo simulates (MJCF) is built from this alone
// (tableMjcf), so that an object kind, a size, a mass or a friction is changed by configuration.
// Units: metres, kilograms, seconds, radians. Frame: the table's top is the plane z = 0, its centre the
// origin; x across the table (its short side), y along it, z up. docs/model.md, "A physical table",
// gives every value's source.
#pragma once
#include <string>

#include "afford/table_world.hpp"

namespace afford::table {

// Throws std::invalid_argument naming the object and field (or the table's field) that is wrong.
void validate(const TableSpec& spec);
// The MJCF text of the whole world: table and rim, light, camera, hand with its actuators, objects (each a
// free body named after the object, resting at the origin of its own frame until placed). validate()s first.
std::string tableMjcf(const TableSpec& spec);

const char* shapeName(Shape s);

// The hand's geoms are of this group, which the agent's camera does not draw (camera.hpp).
constexpr int kHandGroup = 1;

}  // namespace afford::table
