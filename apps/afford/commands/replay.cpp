// afford replay LOG: feed a recorded run into fresh learning processes and compare.
#include <cstdio>
#include <memory>
#include <sstream>

#include "apps/afford/commands.hpp"
#include "experiment/replay/replay.hpp"

namespace afford {

void printLogSkips(long long malformed, long long refused_configs, long long untagged) {
  if (malformed)
    std::printf("skipped: %lld malformed part(s) of the log file (named with their offsets in the warnings)\n", malformed);
  if (refused_configs) std::printf("skipped: %lld RUN_CONFIG event(s) the edge refuses\n", refused_configs);
  if (untagged) std::printf("skipped: %lld event(s) without a valid tag of the bus key\n", untagged);
}

Command replayCommand(CLI::App& app, const FrontDoor& door) {
  struct Args {
    ReplayOptions options;
    std::string into;
  };
  auto a = std::make_shared<Args>();
  auto* replay = app.add_subcommand("replay", "feed a recorded run into fresh learning processes and compare");
  replay->add_option("log", a->options.log_dir, "the run's log folder (logs/<run-id>) or one .lcm file")->required();
  replay->add_option("--run", a->options.run_id, "the run to replay, in a log that holds several (default: the first)");
  replay->add_option("--bus-key", a->options.bus_key,
                     "the key of the bus the log was recorded on (an lcm-logger recording of a keyed bus): "
                     "only events with its tag are replayed");
  replay->add_option("--into", a->into,
                     "processes to replay, comma-separated: predictors, motivation, planner "
                     "(default: predictors and the run's decider)");
  return {replay, [a, &door] {
            std::stringstream ss(a->into);
            for (std::string p; std::getline(ss, p, ',');)
              if (!p.empty()) a->options.into.push_back(p);
            const ReplayResult r = replayRun(a->options, *door.log);
            std::printf("run: %s (%s)\nevents: %lld%s\n", r.run_id.c_str(), r.extrinsic ? "extrinsic" : "intrinsic",
                        static_cast<long long>(r.events), r.torn_bytes ? " (then an incomplete event, skipped)" : "");
            if (!r.incomplete.empty()) std::printf("the log is incomplete: %s\n", r.incomplete.c_str());
            for (const auto& c : r.cut) std::printf("the log is cut: %s\n", c.c_str());
            printLogSkips(r.malformed, r.refused_configs, r.untagged);
            for (const auto& g : r.gaps)
              std::printf("missing from the recording: %s serial%s %lld%s\n", g.channel.c_str(),
                          g.first == g.last ? "" : "s", static_cast<long long>(g.first),
                          g.first == g.last ? "" : (".." + std::to_string(g.last)).c_str());
            if (r.dropped)
              std::printf("refused: %lld recorded message(s) (corrupted; see the warnings)\n",
                          static_cast<long long>(r.dropped));
            if (r.weights_checksum.empty() && r.recorded_checksum.empty() && !r.cut.empty() && !r.extrinsic)
              std::printf("weights_checksum: not compared: the log ends before the run's RESULT\n");
            else if (!r.weights_checksum.empty() || !r.recorded_checksum.empty())
              std::printf("weights_checksum: %s\nrecorded: %s\n",
                          r.weights_checksum.empty() ? "(not reached: the replay stopped before the end)"
                                                     : r.weights_checksum.c_str(),
                          r.recorded_checksum.empty() ? "(none in the log)" : r.recorded_checksum.c_str());
            if (!r.decider_skipped.empty())
              std::printf("decider not replayed: %s\n", r.decider_skipped.c_str());
            else
              std::printf("decisions: %lld replayed, %lld recorded, %lld differing\n", static_cast<long long>(r.decisions),
                        static_cast<long long>(r.decisions_recorded), static_cast<long long>(r.decisions_differing));
            if (r.phase == Phase::Goals) {
              if (!r.goals_skipped.empty())
                std::printf("goal chooser not replayed: %s\n", r.goals_skipped.c_str());
              else
                std::printf("goals: %lld replayed, %lld recorded, %lld differing\n", static_cast<long long>(r.goals),
                            static_cast<long long>(r.goals_recorded), static_cast<long long>(r.goals_differing));
            }
            if (r.ok())
              std::printf("replay equals the record\n");
            else if (!r.consistent())
              std::printf("REPLAY DIFFERS FROM THE RECORD\n");
            else if (!r.cut.empty())
              std::printf("THE LOG IS CUT: it is not the whole run (what is missing is above); what it holds "
                          "replays as recorded\n");
            else
              std::printf("replay equals the record as far as it goes, but the record is %s\n",
                          r.gaps.empty() ? "incomplete" : "missing messages (above)");
            return r.ok() ? 0 : 1;
          }};
}

}  // namespace afford
