#include "experiment/execute/agents.hpp"

#include "experiment/schema/codec.hpp"

#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>

#include "afford/version.hpp"
#include "afford/checksum.hpp"
#include "afford/config.hpp"
#include "experiment/run/group.hpp"
#include "afford/processes.hpp"
#include "experiment/run/outcome.hpp"

namespace afford {
namespace fs = std::filesystem;
using nlohmann::json;

std::vector<fs::path> checkpointFiles(const std::string& checkpoint) {
  std::vector<fs::path> out;
  const fs::path dir = fs::path(checkpoint).parent_path();
  const std::string stem = fs::path(checkpoint).stem().string();
  std::error_code ec;
  for (const auto& f : fs::directory_iterator(dir, ec))
    if (f.path().extension() == ".ckpt" && f.path().filename().string().rfind(stem, 0) == 0) out.push_back(f.path());
  return out;
}

std::string agentKey(const std::string& config_yaml) {
  YAML::Node node = YAML::Load(config_yaml);
  node.remove("experiment");
  node.remove("planner");
  if (node["run"]) {
    node["run"].remove("checkpoint");
    node["run"].remove("record");
    node["run"].remove("checkpoint_after_actions");
  }
  const std::string text = std::string(affordVersion()) + "\n" + codeFingerprint() + "\n" + emitYaml(node);
  Fnv1a h;
  h.add(text.data(), text.size());
  return h.hex();
}

AgentStore::AgentStore(std::string root) : root_(std::move(root)) {}

namespace {

// A stored agent's outcome.json: whose run it was, of which experiment, its content key, and its outcome.
struct StoredAgent {
  std::string run_id, experiment, key;
  RunOutcome outcome;
  std::optional<std::string> afford_version;  // the build that stored it (from 0.2.0)
  template <class V>
  void visit(V& v) {
    v("run_id", run_id);
    v("experiment", experiment);
    v("key", key);
    v("outcome", outcome);
    v("afford_version", afford_version);
  }
};

}  // namespace

std::optional<RunOutcome> AgentStore::find(const std::string& key, std::int64_t after_actions,
                                            std::uintmax_t max_bytes) const {
  const fs::path dir = fs::path(root_) / key;
  const fs::path file = dir / "outcome.json";
  std::error_code ec;
  if (!fs::exists(file, ec)) return std::nullopt;
  StoredAgent stored;
  try {
    stored = fromJsonOf<StoredAgent>(readJsonFile(file, max_bytes), file.string());
  } catch (const std::exception& e) {
    throw ConfigError("the stored agent " + file.string() + " cannot be read (" + e.what() +
                      "): remove its folder (afford clean) or run with --no-reuse-agents");
  }
  RunOutcome r = std::move(stored.outcome);
  r.reused_from = stored.run_id;
  r.checkpoint = (dir / "predictors.ckpt").string();
  // Nothing of the stored run's running is this run's: no log, no time, no memory (a run reported with the log
  // folder, the speed and the memory of the run it was taken from said what did not happen).
  r.log_dir.clear();
  r.log_bytes = 0;
  r.wall_seconds = r.run_seconds = 0;
  r.peak_rss_kb.clear();
  if (!fs::exists(r.checkpoint)) return std::nullopt;
  if (after_actions > 0 && !fs::exists(actionsCheckpoint(r.checkpoint, after_actions))) return std::nullopt;
  return r;
}

void AgentStore::keep(const std::string& key, const std::string& run_id, const std::string& experiment,
                      const RunOutcome& r) const {
  if (!r.ok || r.checkpoint.empty() || !fs::exists(r.checkpoint)) return;
  const fs::path dir = fs::path(root_) / key;
  // Unique among runners sharing the log root, on this host or another.
  char host[256] = {};
  gethostname(host, sizeof host - 1);
  const std::string mine = std::string(".part.") + host + "." + std::to_string(getpid());
  // Each checkpoint file of the run, as predictors<suffix> in `folder` (a hard link where it can).
  const std::size_t stem = fs::path(r.checkpoint).stem().string().size();
  auto link = [&](const fs::path& folder, bool only_missing) {
    for (const fs::path& f : checkpointFiles(r.checkpoint)) {
      const fs::path to = folder / ("predictors" + f.filename().string().substr(stem));
      if (only_missing && fs::exists(to)) continue;
      const fs::path tmp = only_missing ? fs::path(to.string() + mine) : to;  // renamed into place: never half a file
      std::error_code ec;
      fs::create_hard_link(f, tmp, ec);
      if (ec) fs::copy_file(f, tmp, fs::copy_options::overwrite_existing);
      if (only_missing) fs::rename(tmp, to);
    }
  };
  if (fs::exists(dir)) {  // kept already (the same agent): add what it lacks, e.g. an after-N-actions checkpoint
    link(dir, true);
    return;
  }
  const fs::path part = fs::path(root_) / (key + mine);
  fs::remove_all(part);
  fs::create_directories(part);
  link(part, false);
  RunOutcome kept = r;
  kept.reused_from.clear();
  writeWhole(part / "outcome.json", toJsonOf(StoredAgent{run_id, experiment, key, kept, std::string(affordVersion())}).dump() + "\n");
  std::error_code ec;
  fs::rename(part, dir, ec);
  if (ec) fs::remove_all(part);  // another runner kept the same agent first
}

// Intrinsic runs not finished (nor run by another shard) whose agent is
// stored (the same content key) are not run: they take the stored outcome and
// checkpoints, kept as finished.
void takeStoredAgents(const std::vector<PlannedRun>& runs, int after_actions, PhaseRuns& phase,
                      const AgentStore& agents, const std::string& out_dir, spdlog::logger& log, bool watched) {
  std::size_t taken = 0;
  for (const auto& p : runs) {
    if (phase.finished[p.index] || (!phase.elsewhere.empty() && phase.elsewhere[p.index])) continue;
    auto r = agents.find(agentKey(p.spec.config_yaml), after_actions, mostOutcomeBytes(p.spec));
    if (!r) continue;
    keepOutcome(out_dir, p.spec.run_id, *r);
    phase.outcomes[p.index] = std::move(*r);
    phase.finished[p.index] = 1;
    ++taken;
  }
  if (taken)
    log.info("{} of {} intrinsic run(s) reuse a stored agent of the same configuration and seed ({}): they do not "
             "run, nothing of theirs goes on the bus; to run them anew (a fault drill, a check that a run reproduces), "
             "give --no-reuse-agents", taken, runs.size(), agents.root());
  if (taken && watched)
    log.warn("--watch: the page will not show {} intrinsic run(s) learning: their agents were stored by an earlier run "
             "and are taken, not trained again; it shows their tests only. To watch them learn, run the same command "
             "again with --no-reuse-agents (it trains them again)", taken);
}

void storeAgent(const PlannedRun& p, const PhaseRuns& phase, const AgentStore& agents, spdlog::logger& log) {
  const RunOutcome& r = phase.outcomes[p.index];
  if (!phase.finished[p.index] || !r.ok || !r.reused_from.empty()) return;
  try {
    agents.keep(agentKey(p.spec.config_yaml), p.spec.run_id, p.spec.experiment, r);
  } catch (const std::exception& e) {  // the experiment's own results stand; only the reuse is lost
    log.warn("run '{}': its agent could not be stored for reuse ({})", p.spec.run_id, e.what());
  }
}

std::shared_ptr<AgentClaims::Claim> AgentClaims::claim(const std::string& key, std::int64_t after_actions,
                                                       const std::string& run_id, std::shared_ptr<Claim>& mine) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto [from, to] = claims_.equal_range(key);
  for (auto it = from; it != to; ++it)  // one that writes the checkpoint this run needs, if it needs one
    if (after_actions <= 0 || it->second->after_actions == after_actions) return it->second;
  mine = std::make_shared<Claim>(Claim{run_id, after_actions, false});
  claims_.emplace(key, mine);
  return nullptr;
}

void AgentClaims::settle(const std::shared_ptr<Claim>& c) {
  if (!c) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    c->settled = true;
  }
  settled_.notify_all();
}

void AgentClaims::wait(const std::shared_ptr<Claim>& c) {
  std::unique_lock<std::mutex> lock(mutex_);
  settled_.wait(lock, [&] { return c->settled; });
}

}  // namespace afford
