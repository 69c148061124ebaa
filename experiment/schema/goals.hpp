// summary.json's goals of a GOALS agent (systems.GOALS.goals): part of
// summary.hpp's structure, in a file of its own.
#pragma once
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "experiment/schema/codec.hpp"

namespace afford {

// What became of a GOALS agent's goals (docs/model.md#goals-of-its-own), per
// module (explore, colour, move, colour_place), over the runs of a system.
struct GoalModuleSummary {
  std::int64_t set = 0, reached = 0, actions = 0;  // goals ended, reached, actions spent on them
  std::int64_t found = 0;  // ... found reached when set (no action taken): left out of the competence
  // Competence (goals reached / goals ended, of those pursued: found reached when set left out) in the first
  // and the last tenth of the runs' steps, and in each curve interval (null where none ended); the share of
  // the goals pursued that are this module's.
  Nullable<double> first_tenth, last_tenth;
  // Per curve interval: goals reached per run (the mean over runs).
  std::vector<Nullable<double>> competence;
  std::vector<double> chosen;
  std::vector<double> reached_per_run;
  template <class V>
  void visit(V& v) {
    v("set", set);
    v("reached", reached);
    v("actions", actions);
    v("found", found);
    v("first_tenth", first_tenth);
    v("last_tenth", last_tenth);
    v("competence", competence);
    v("chosen", chosen);
    v("reached_per_run", reached_per_run);
  }
};
struct GoalsSummary {
  std::vector<std::int64_t> steps;  // the first step of each curve interval
  std::map<std::string, GoalModuleSummary> modules;
  template <class V>
  void visit(V& v) {
    v("steps", steps);
    v("modules", modules);
  }
};

}  // namespace afford
