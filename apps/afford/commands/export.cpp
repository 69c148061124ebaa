// afford export LOG --mcap FILE: a recorded run as an MCAP file for Foxglove, PlotJuggler or Rerun.
#include <cstdio>
#include <memory>
#include <string>

#include "afford/process_main.hpp"
#include "apps/afford/commands.hpp"
#include "experiment/export/export.hpp"

namespace afford {

namespace {

void printExport(const ExportResult& r) {
  const char* phase = r.phase == Phase::Extrinsic ? "extrinsic" : r.phase == Phase::Goals ? "goals" : "intrinsic";
  std::printf("run: %s (%s)\nevents: %lld%s\n", r.run_id.c_str(), phase, static_cast<long long>(r.events),
              r.torn_bytes ? " (then an incomplete event, skipped)" : "");
  if (!r.incomplete.empty()) std::printf("the log is incomplete: %s\n", r.incomplete.c_str());
  for (const std::string& c : r.cut) std::printf("the log is cut: %s\n", c.c_str());
  if (!r.cut.empty()) std::printf("so the file holds the run only as far as the log goes\n");
  std::printf("wrote %s: %lld messages on %zu topics, %llu chunks (%s, %llu bytes of records), %llu bytes\n",
              r.file.c_str(), static_cast<long long>(r.messages), r.topics.size(),
              static_cast<unsigned long long>(r.chunks), r.compression.empty() ? "uncompressed" : r.compression.c_str(),
              static_cast<unsigned long long>(r.record_bytes), static_cast<unsigned long long>(r.bytes));
  for (const ExportedTopic& t : r.topics) {
    std::printf("  %-24s %-26s %8lld", t.topic.c_str(), t.schema.empty() ? "-" : t.schema.c_str(),
                static_cast<long long>(t.messages));
    if (t.skipped)
      std::printf("   skipped %lld (the first: %s)", static_cast<long long>(t.skipped), t.first_skipped.c_str());
    std::printf("\n");
  }
  if (r.skipped)
    std::printf("skipped: %lld message(s) that do not decode or that the edge refuses (see the warnings)\n",
                static_cast<long long>(r.skipped));
  printLogSkips(r.malformed, r.refused_configs, r.untagged);
  if (r.left_out)
    std::printf("left out: %lld event(s) before the run's RUN_CONFIG or of other runs\n",
                static_cast<long long>(r.left_out));
}

}  // namespace

Command exportCommand(CLI::App& app, const FrontDoor& door) {
  auto o = std::make_shared<ExportOptions>();
  auto* cmd = app.add_subcommand("export", "write a recorded run as an MCAP file (Foxglove, PlotJuggler, Rerun)");
  cmd->add_option("log", o->log, "the run's log folder (logs/<run-id>) or one .lcm file")->required();
  cmd->add_option("--mcap", o->mcap, "the MCAP file to write (a new file: an existing one is never overwritten)")
      ->required();
  cmd->add_option("--run", o->run_id, "the run to export, in a log that holds several (default: the first)");
  cmd->add_option("--bus-key", o->bus_key,
                  "the key of the bus the log was recorded on (an lcm-logger recording of a keyed bus): "
                  "only events with its tag are exported");
  auto compression = std::make_shared<std::string>("zstd");
  cmd->add_option("--compression", *compression, "the chunks' compression: zstd (the default) or none")
      ->check(CLI::IsMember({"zstd", "none"}));
  return {cmd, [o, compression, &door] {
            o->compression = *compression == "none" ? "" : *compression;
            installStopHandlers();  // Ctrl-C: nothing half-written left
            printExport(exportMcap(*o, *door.log));
            return 0;
          }};
}

}  // namespace afford
