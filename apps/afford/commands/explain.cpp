// afford explain LOG: why an extrinsic test ended as it did; or a folder of tests, summarised.
#include <cstdio>
#include <memory>

#include "apps/afford/commands.hpp"
#include "afford/config.hpp"
#include "experiment/present/explain_text.hpp"

namespace afford {

Command explainCommand(CLI::App& app, const FrontDoor& door) {
  struct Args {
    std::string log, run, bus_key;
    bool json = false, by_agent = false;
  };
  auto a = std::make_shared<Args>();
  auto* explain = app.add_subcommand(
      "explain", "why an extrinsic test ended as it did, from its log; or every test in a folder of logs, summarised");
  explain
      ->add_option("log", a->log,
                   "the test's log folder (<log-root>/<run-id>) or one .lcm file; or a folder of run log folders "
                   "(an experiment's --log-root) for a summary")
      ->required();
  explain->add_option("--run", a->run, "the test to explain, in a log that holds several (default: the first)");
  explain->add_option("--bus-key", a->bus_key,
                      "the key of the bus the log was recorded on (an lcm-logger recording of a keyed bus)");
  explain->add_flag("--json", a->json, "print one JSON object (for scripts) instead of text");
  explain->add_flag("--by-agent", a->by_agent,
                    "with a folder of run logs: by system, scenario and sub-goal, then by trained agent, how often it "
                    "was reached, why not, and each agent's closest predicted effect");
  return {explain, [a, &door] {
            const std::shared_ptr<const BusKey> key = a->bus_key.empty() ? nullptr : busKeyFrom(a->bus_key);
            if (isLogRoot(a->log)) {
              if (!a->run.empty())
                throw ConfigError("--run picks a run in one log, but " + a->log + " is a folder of run logs");
              const ExplainSummary s = explainLogRoot(a->log, *door.log, key.get());
              if (a->by_agent)
                std::printf("%s", a->json ? (byAgentJson(s).dump(2) + "\n").c_str() : byAgentText(s).c_str());
              else
                std::printf("%s", a->json ? (summaryJson(s).dump(2) + "\n").c_str() : summaryText(s).c_str());
              return s.errors.empty() ? 0 : 1;  // a log that could not be explained is named, and fails the summary
            }
            if (a->by_agent)
              throw ConfigError("--by-agent summarises a folder of run logs, but " + a->log + " is one run's log");
            const Explanation e = explainLog(a->log, a->run, *door.log, key.get());
            std::printf("%s", a->json ? (explanationJson(e).dump(2) + "\n").c_str() : explanationText(e).c_str());
            return 0;
          }};
}

}  // namespace afford
