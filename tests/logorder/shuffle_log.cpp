// shuffle-log IN OUT [--window N] [--seed S] [--segments K] [--move-config]: the run's log at IN
// (a folder of segments or one .lcm file) written into the new folder OUT with
// its channels interleaved anew (tests/logorder/shuffle.hpp), for the tests
// that compare what a tool makes of a log and of the same log shuffled.
#include <CLI/CLI.hpp>

#include <cstdio>

#include "tests/logorder/shuffle.hpp"

int main(int argc, char** argv) {
  CLI::App app{"a run's log with its channels interleaved anew, each in its own order (for the tests)", "shuffle-log"};
  std::string in, out;
  afford::testing::ShuffleOptions o;
  app.add_option("in", in, "a run's log folder or one .lcm file")->required();
  app.add_option("out", out, "the folder to write (new)")->required();
  app.add_option("--window", o.window, "the most steps a channel runs ahead of another")->capture_default_str();
  app.add_option("--seed", o.seed, "the draw's seed")->capture_default_str();
  app.add_option("--segments", o.segments, "segments written (log.00.lcm, ...)")->capture_default_str();
  app.add_flag("--move-config", o.config_too, "the RUN_CONFIG interleaved too (a logger writes it first)");
  CLI11_PARSE(app, argc, argv);
  try {
    if (std::filesystem::exists(out)) throw std::runtime_error(out + " exists");
    const afford::testing::ShuffleReport r = afford::testing::shuffleLog(in, out, o);
    std::printf("%lld events, %lld moved, a channel up to %lld steps ahead of another, in %d segment(s)\n",
                static_cast<long long>(r.events), static_cast<long long>(r.moved),
                static_cast<long long>(r.most_ahead), o.segments);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "shuffle-log: %s\n", e.what());
    return 1;
  }
  return 0;
}
