// DIR/experiment.json: what an experiment keeps of itself so that an
// interrupted one can be resumed and a finished one read (its request, the
// fingerprint of its plan, how it stopped), every key declared once and
// read strictly (experiment/schema/codec.hpp). The runs' outcomes beside it
// are run/outcome.hpp's.
#pragma once
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "experiment/execute/execute.hpp"
#include "experiment/plan/plan.hpp"
#include "experiment/schema/summary.hpp"
#include "experiment/stored/request.hpp"

namespace afford {

std::filesystem::path statePath(const std::filesystem::path& out);

// A planned run as the experiment keeps it: its id and the FNV-1a of its configuration. A resumed
// experiment must plan the very same runs.
struct RunFingerprint {
  std::string run_id, config;
  bool operator==(const RunFingerprint& o) const { return run_id == o.run_id && config == o.config; }
  template <class V>
  void visit(V& v) {
    v("run_id", run_id);
    v("config", config);
  }
};
// Where a stop signal cut the experiment.
struct StoppedAt {
  std::string signal, phase;
  std::vector<CutRun> cut;
  template <class V>
  void visit(V& v) {
    v("signal", signal);
    v("phase", phase);
    v("cut", cut);
  }
};

// DIR/experiment.json: every key declared once (visit), read strictly.
struct ExperimentState {
  std::string experiment;                   // its name
  std::string cwd;                          // where it was started (relative paths are from there)
  std::optional<std::string> out;           // --out as given there (from 0.2.0; 0.1.0 named it in `resume` alone)
  ExperimentRequest options;                // as it runs (experiment/request.hpp)
  std::vector<RunFingerprint> runs;         // the intrinsic runs planned
  std::optional<std::vector<RunFingerprint>> tests;  // the extrinsic tests, once planned
  std::vector<StoppedAt> interruptions;
  std::vector<MovedAside> moved_aside;
  std::optional<std::vector<std::string>> merged_from;  // afford merge: the shards' folders
  std::string state = "running";            // running, interrupted or finished
  std::string resume;                       // the command that continues it
  std::optional<std::string> afford_version;  // the build that wrote it last (afford --version); absent: 0.1.0
  std::optional<std::string> planned_by;      // the build that planned it (its fingerprints); absent: 0.1.0
  std::optional<std::vector<PathMove>> moved;  // from 0.2.0: where it was resumed after its folder moved
  template <class V>
  void visit(V& v) {
    v("experiment", experiment);
    v("cwd", cwd);
    v("out", out);
    v("options", options);
    v("runs", runs);
    v("tests", tests);
    v("interruptions", interruptions);
    v("moved_aside", moved_aside);
    v("merged_from", merged_from);
    v("state", state);
    v("resume", resume);
    v("afford_version", afford_version);
    v("planned_by", planned_by);
    v("moved", moved);
  }
};
inline constexpr std::uintmax_t kMostStateBytes = 64u << 20;  // an experiment.json (its plan's fingerprint)

// DIR/experiment.json, read only if it is a regular file of a sane size, strictly; ConfigError naming it.
ExperimentState readState(const std::filesystem::path& out);
// ... written whole (aside, then renamed), with the version of this build.
void writeState(const std::filesystem::path& out, const ExperimentState& state);

// The fingerprints of the runs planned; refused when they are not those stored (naming the first that differs).
// `moves`: the paths of their configurations as they were stored (a moved folder's fingerprints are those of
// the paths it was started with).
// `planned_by`: the release whose configurations they are to match: keys added since (config/migrations.yaml)
// that hold the value that release had are left out, as it wrote them ("": this build's).
std::vector<RunFingerprint> fingerprint(const std::vector<PlannedRun>& runs, const std::vector<PathMove>& moves = {},
                                        const std::string& planned_by = "");
void refuseOtherPlan(const std::vector<RunFingerprint>& stored, const std::vector<RunFingerprint>& now,
                     const std::string& what);

}  // namespace afford
