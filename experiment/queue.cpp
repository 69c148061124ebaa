// Several experiments side by side in one queue of job slots (experiment/pipeline.hpp, runQueue).
#include <map>
#include <thread>

#include "afford/process_main.hpp"
#include "experiment/execute/bus_note.hpp"
#include "experiment/run/netns.hpp"
#include <nlohmann/json.hpp>

#include <filesystem>

#include "experiment/pipeline.hpp"

namespace afford {
namespace fs = std::filesystem;

int runQueue(const std::vector<ExperimentRequest>& requests, const std::string& resume, spdlog::logger& log) {
  const auto began = std::chrono::steady_clock::now();
  if (requests.empty()) throw ConfigError("the queue is empty: give experiment names, or a --plan file with entries");
  // Every experiment is checked and planned before any is written or started; a signal stops that too (a table's
  // truth may be estimated while planning).
  installInterruptHandlers("");
  std::vector<Experiment> xs;
  std::map<std::string, std::string> folders;  // out dir -> the experiment writing there
  std::map<std::string, std::string> run_ids;  // run id -> the experiment running it (its log folder)
  for (const ExperimentRequest& r : requests) {
    const std::string name = r.plan.experiment.empty() ? r.write.out_dir : r.plan.experiment;
    try {
      xs.push_back(prepare(r));
    } catch (const ConfigError& e) {
      throw ConfigError("queue entry " + std::to_string(xs.size() + 1) + " (" + name + "): " + e.what());
    }
    const std::string dir = fs::weakly_canonical(fs::absolute(r.write.out_dir)).string();
    if (const auto [it, fresh] = folders.emplace(dir, name); !fresh)
      throw ConfigError("queue entries " + it->second + " and " + name + " would both write to " + r.write.out_dir +
                        ": give each its own --out");
    for (const PlannedRun& p : xs.back().runs)
      if (const auto [it, fresh] = run_ids.emplace(p.spec.run_id, name); !fresh)
        throw ConfigError("queue entries " + it->second + " and " + name + " both plan run '" + p.spec.run_id +
                          "' (one log folder for two runs): give them other --run-prefix values");
  }
  const HostRequest& host = xs.front().o.host;
  Shared share;
  if (host.transport == "udpm") share.network = prepareNetwork(host.netns);
  if (host.transport == "udpm" && host.on_bus) host.on_bus(slotUrls(host));
  installInterruptHandlers(resume);
  SlotPool pool(host, true, "queue of " + std::to_string(xs.size()) + " experiment(s), runs and tests");
  AgentClaims claims;
  Turns turns;
  share.pool = &pool;
  share.claims = &claims;
  share.turns = &turns;
  log.info("queue: {} experiment(s) side by side on {} job slot(s) over {}", xs.size(), host.jobs, host.transport);
  std::vector<int> codes(xs.size(), 0);
  std::vector<std::thread> threads;
  for (std::size_t k = 0; k < xs.size(); ++k)
    threads.emplace_back([&, k] {
      Shared mine = share;
      mine.position = k;
      try {
        codes[k] = runPrepared(xs[k], std::chrono::steady_clock::now(), log, mine);
      } catch (const ConfigError& e) {
        log.error("{}: {}", xs[k].plan().exp.name, e.what());
        codes[k] = 2;
      } catch (const std::exception& e) {
        log.error("{}: {}", xs[k].plan().exp.name, e.what());
        codes[k] = 1;
      }
      turns.pass(k);  // one that stopped before claiming its agents lets the next claim
    });
  for (auto& t : threads) t.join();
  int code = 0;
  for (std::size_t k = 0; k < xs.size(); ++k) {
    if (codes[k] != 0) log.warn("queue: {} ({}) exited with status {}", xs[k].plan().exp.name, xs[k].out().string(), codes[k]);
    code = std::max(code, codes[k]);
  }
  if (stopSignal() || !pool.halted().empty()) log.warn("to resume the whole queue: {}", resume);
  log.info("queue: {} experiment(s) in {}", xs.size(),
           durationText(std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count()));
  return code;
}

}  // namespace afford
