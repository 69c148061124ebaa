// The truth of the table world: each (object, action) affordance, the probability that the action's goal
// is reached on the object, estimated by trials of the motor primitive on the object alone on the table,
// from random poses (and, for push and carry, random places), with a 95% interval. The learned affordances
// are measured against it: in this world no table is typed in, physics gives it.
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "environment/table/primitives.hpp"

namespace afford::table {

void validate(const TruthSpec& t, const TableSpec& table);

struct TruthCell {
  int successes = 0, trials = 0;
  double rate() const { return trials ? static_cast<double>(successes) / trials : 0.0; }
  // Wilson's score interval at 95%.
  double low() const;
  double high() const;
};

struct TruthTable {
  std::vector<std::string> objects;                  // the spec's objects, in order
  std::vector<std::array<TruthCell, kTableActions>> cells;  // [object][action]
};

// `trials` trials of each action on each object (each alone on the table), drawn by (seed, trial, purpose);
// `only` restricts the objects (their indices; empty: all). `progress` is told each finished (object, action).
TruthTable estimateTruth(const TableSpec& table, const PrimitiveSpec& primitives, const TruthSpec& truth,
                         std::int64_t seed, int trials, const std::vector<int>& only = {},
                         const std::function<void(int object, int action)>& progress = {});

}  // namespace afford::table
