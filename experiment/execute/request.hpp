// What hosts an experiment's runs: how many at a time, over which transport,
// with which processes, and which of the runs (a shard). Nothing here changes
// what a run computes: the same plan hosted two ways gives the same results.
#pragma once
#include <map>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "experiment/run/netns.hpp"
#include "experiment/schema/codec.hpp"

namespace afford {

// Where an intrinsic run's learning curve stands: its affordance table at `step`, `mae` from the run's target.
struct CurvePoint {
  std::string run_id, system;
  std::size_t run = 0;  // its index in the plan's runs
  std::int64_t step = 0;
  double mae = 0;
};

struct HostRequest {
  int jobs = 1;
  std::string transport = "udpm";          // udpm | memq
  bool reuse_agents = true;                // take stored agents of the same content key (execute/agents.hpp)
  NetnsMode netns = NetnsMode::Auto;
  int base_port = 7700;
  std::string process_log_level = "info";  // for the processes (udpm) / in-process nodes (memq: warn)
  double stall_seconds = 30;               // a run whose processes say nothing this long failed
  std::string progress = "auto";           // auto | terminal | lines | none (execute/progress.hpp)
  double progress_every = -1;              // seconds between progress draws (< 0: by mode)
  std::string attach;                      // run on this bus with processes started by hand (no group, one job)
  // --process NAME=CMD: the runner starts CMD (a shell command, the standard arguments appended) in place of
  // the shipped afford-NAME (udpm only)
  std::map<std::string, std::string> processes;
  std::string bus_key;                     // key file of a keyed bus (afford/auth.hpp; "": $AFFORD_BUS_KEY, or none)
  int shard_index = 0, shard_count = 0;    // --shard i/n: run intrinsic run k (and its tests) iff k mod n == i
  // Told each point of every intrinsic run's curve as it comes, from the slot's thread (the Python package's
  // afford.run(on_curve=...), which afford.tune prunes with); not kept. It must not throw.
  std::function<void(const CurvePoint&)> on_curve;
  // Where the progress lines go in the place of stderr (afford.run: Python's sys.stderr); not kept.
  std::function<void(const std::string&)> progress_to;
  // Told the bus of every job slot once the runs' network is entered, before any run starts, on the thread
  // that entered it (afford experiment --watch listens there); not kept. What it throws stops the experiment.
  std::function<void(const std::vector<std::string>& urls)> on_bus;

  // A shard as an experiment keeps it: {"index": i, "count": n}, or null without shards.
  struct Shard {
    int index = 0, count = 0;
    template <class V>
    void visit(V& v) {
      v("index", index);
      v("count", count);
    }
  };
  // What an experiment keeps of it (DIR/experiment.json): --resume uses it unless given again. The key
  // file is not kept (its path may be gone, or another, when the experiment is resumed).
  template <class V>
  void visit(V& v) {
    v.since("reuse_agents", reuse_agents, false);  // (stored before issue 13: no reuse)
    std::optional<Shard> shard;
    if (shard_count) shard = Shard{shard_index, shard_count};
    visitNullable(v, "shard", shard);
    if constexpr (V::kReads) shard_index = shard ? shard->index : 0, shard_count = shard ? shard->count : 0;
    v.since("processes", processes, std::map<std::string, std::string>());  // (before issue 24: none)
    v("jobs", jobs);
    v("transport", transport);
    v("netns", netns);
    v("base_port", base_port);
    v("process_log_level", process_log_level);
    v("stall_seconds", stall_seconds);
    v.since("progress", progress, std::string("auto"));  // (before issue 13: the default)
    v.since("progress_every", progress_every, -1.0);
    v("attach", attach);
  }
};

// The checks of a request that need no file: each names its option.
void checkHostRequest(const HostRequest& r);

// Which of n intrinsic runs another shard runs (run k iff k mod count != index); empty without shards.
std::vector<char> shardMask(const HostRequest& r, std::size_t n);

}  // namespace afford
