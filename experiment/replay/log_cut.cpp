#include "experiment/replay/log_cut.hpp"

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>

#include "experiment/run/outcome.hpp"
#include "afford/decode.hpp"
#include "afford/edge.hpp"
#include "afford/protocol.hpp"
#include "afford/run_config_t.hpp"
#include "afford/run_control_t.hpp"

namespace afford {
namespace fs = std::filesystem;

void RunReach::add(const LogEvent& e) {
  const BoundsContext ctx{protocol_, nullptr};
  std::string why;
  if (!configured_) {
    run_config_t m{};
    if (e.channel != ch::runConfig.name || !decodeChecked(e.data.data(), e.data.size(), ctx, m, why)) return;
    configured_ = true;
    digest_ = m.digest;
    try {
      const RunConfig config = parseRunConfigText(m.config_yaml);
      phase_ = config.phase;
      steps_ = config.steps;
    } catch (const std::exception&) {
      // (a configuration that does not read: how many steps the run has is not known)
    }
    return;
  }
  if (e.channel == ch::runControl.name) {
    run_control_t c{};
    if (decodeChecked(e.data.data(), e.data.size(), ctx, c, why) && c.command == run_control_t::STOP &&
        c.config_digest == digest_)
      stopped_ = true;
    return;
  }
  RunHeader h;
  if (!isSerialChannel(e.channel) || !peekRunHeader(e.data.data(), e.data.size(), h)) return;
  last_step_ = std::max(last_step_, h.step);
  if (e.channel == (phase_ == Phase::Extrinsic ? ch::extrinsicResult.name : ch::result.name)) ended_ = true;
}

namespace {

std::string n(std::int64_t v) { return std::to_string(v); }

// What the manifest beside the log says against the segments read. Only a
// manifest its logger closed counts what the log holds (complete, or with
// the reason it is not); one of a log none of whose files was read is
// another log's.
void manifestSays(const fs::path& log, const std::vector<SegmentRead>& read, std::vector<std::string>& cut) {
  const fs::path file = (fs::is_directory(log) ? log : log.parent_path()) / "manifest.json";
  const nlohmann::json m = readManifest(file);
  if (m.is_discarded() || !m.is_object() || !m.contains("segments") || !m["segments"].is_array() ||
      m["segments"].empty())
    return;
  const bool closed = m.value("complete", false) || m.contains("incomplete");
  std::vector<std::string> named;
  for (const auto& s : m["segments"])
    if (s.is_string()) named.push_back(s.get<std::string>());
  const auto readAs = [&](const std::string& name) {
    return std::find_if(read.begin(), read.end(), [&](const SegmentRead& r) { return r.file.filename() == name; });
  };
  if (!closed || named.empty() ||
      std::none_of(named.begin(), named.end(), [&](const std::string& s) { return readAs(s) != read.end(); }))
    return;
  for (const std::string& s : named)
    if (readAs(s) == read.end()) cut.push_back("the segment " + s + " its manifest names is missing");
  const auto last = readAs(named.back());
  if (last == read.end() || !m.contains("events") || !m["events"].is_number_integer()) return;
  const std::int64_t events = m["events"].get<std::int64_t>();
  const std::int64_t bytes = m.value("payload_bytes", last->payload_bytes);
  if (last->events == events && last->payload_bytes == bytes) return;
  const std::string counts = "its manifest counts " + n(events) + " events (" + n(bytes) + " payload bytes) in " +
                             named.back() + ", the log holds " + n(last->events) + " (" + n(last->payload_bytes) + ")";
  cut.push_back(last->events < events ? counts + ": " + n(events - last->events) + " events missing"
                                      : counts + ": the log is not the one its manifest was written for");
}

// What the run's own messages say: how far it got, and whether its end is there.
void runSays(const RunReach& run, std::vector<std::string>& cut) {
  if (!run.configured()) return;
  if (run.phase() == Phase::Extrinsic) {
    if (!run.ended())
      cut.push_back("the test's end is not in the log: its EXTRINSIC_RESULT and STOP are missing (its messages go " +
                    (run.lastStep() < 0 ? std::string("no further than its start")
                                        : "as far as planner iteration " + n(run.lastStep())) +
                    (run.steps() >= 0 ? ", of at most " + n(run.steps()) + ")" : ")"));
    else if (!run.stopped())
      cut.push_back("the test's end is not all in the log: the STOP after its EXTRINSIC_RESULT is missing");
    return;
  }
  if (!run.ended() && run.steps() >= 0 && run.lastStep() < run.steps())
    cut.push_back(run.lastStep() < 0 ? "the log ends before the run's first step: all " + n(run.steps()) +
                                           " steps missing"
                                     : "the log ends at step " + n(run.lastStep()) + " of " + n(run.steps()) + ": " +
                                           n(run.steps() - run.lastStep()) + " steps missing");
  if (!run.ended())
    cut.push_back("the run's end is not in the log: its RESULT and STOP are missing");
  else if (!run.stopped())
    cut.push_back("the run's end is not all in the log: the STOP after its RESULT is missing");
}

}  // namespace

std::vector<std::string> logCut(const fs::path& log, const std::vector<SegmentRead>& read, const RunReach& run) {
  std::vector<std::string> cut;
  manifestSays(log, read, cut);
  const bool empty =
      std::all_of(read.begin(), read.end(), [](const SegmentRead& r) { return r.events == 0 && r.torn_bytes == 0; });
  if (empty && cut.empty()) cut.push_back("the log holds no event: the whole run is missing");
  // An event cut short ends the last segment: the log was cut there, or its writer killed (in an earlier
  // segment, a logger killed and restarted: the next segment goes on from it).
  if (!read.empty() && read.back().torn_bytes > 0)
    cut.push_back("the last event of " + read.back().file.filename().string() + " is cut short: only its first " +
                  n(read.back().torn_bytes) + " bytes are there, the rest is missing");
  runSays(run, cut);
  return cut;
}

std::string joinedCut(const std::vector<std::string>& cut) {
  std::string out;
  for (const std::string& c : cut) out += (out.empty() ? "" : "; ") + c;
  return out;
}

}  // namespace afford
