#include "experiment/run/outcome.hpp"

#include <fstream>

#include "afford/config.hpp"

namespace afford {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {
fs::path outcomePath(const fs::path& out, const std::string& run_id) { return out / "runs" / (run_id + ".json"); }
}  // namespace

// `text` into `path`, whole or not at all: written beside it, then renamed
// over it (an interruption leaves the previous version or the new one).
void writeWhole(const fs::path& path, const std::string& text) {
  const fs::path part = path.string() + ".part";
  {
    std::ofstream f(part, std::ios::binary | std::ios::trunc);
    f << text;
    f.close();
    if (!f) throw std::runtime_error("cannot write " + part.string());
  }
  fs::rename(part, path);
}

json outcomeToJson(const RunOutcome& r) {
  json curve = json::array();
  for (const auto& s : r.curve) curve.push_back({{"step", s.step}, {"affordance", s.affordance}});
  json goals = json::array();
  for (const auto& g : r.extrinsic.sub_goals)
    goals.push_back({{"x", g.x}, {"y", g.y}, {"iterations", g.iterations}, {"actions_checked", g.actions_checked},
                     {"actions_taken", g.actions_taken}, {"reached", g.reached}});
  return {{"ok", r.ok},
          {"error", r.error},
          {"weights_checksum", r.weights_checksum},
          {"checkpoint", r.checkpoint},
          {"reused_from", r.reused_from},
          {"curve", curve},
          {"executed", r.executed},
          {"successes", r.successes},
          {"looks", r.looks},
          {"replayed", r.replayed},
          {"replayed_effects", r.replayed_effects},
          {"revisits", r.revisits},
          {"log_dir", r.log_dir},
          {"wall_seconds", r.wall_seconds},
          {"run_seconds", r.run_seconds},
          {"peak_rss_kb", r.peak_rss_kb},
          {"log_bytes", r.log_bytes},
          {"extrinsic",
           {{"scenario", r.extrinsic.scenario},
            {"success", r.extrinsic.success},
            {"completion", r.extrinsic.completion},
            {"attempts", r.extrinsic.attempts},
            {"utility", r.extrinsic.utility},
            {"sub_goals", goals}}}};
}

RunOutcome outcomeFromJson(const json& j) {
  RunOutcome r;
  r.ok = j.at("ok").get<bool>();
  r.error = j.at("error").get<std::string>();
  r.weights_checksum = j.at("weights_checksum").get<std::string>();
  r.checkpoint = j.at("checkpoint").get<std::string>();
  r.reused_from = j.value("reused_from", std::string());  // outcomes kept before issue 13 have none
  for (const auto& s : j.at("curve"))
    r.curve.push_back({s.at("step").get<std::int64_t>(), s.at("affordance").get<std::vector<std::vector<double>>>()});
  r.executed = j.at("executed").get<std::vector<std::int64_t>>();
  r.successes = j.at("successes").get<std::vector<std::int64_t>>();
  r.looks = j.value("looks", 0);  // outcomes kept before issue 11 have none of these
  r.replayed = j.value("replayed", std::int64_t{0});
  r.replayed_effects = j.value("replayed_effects", std::int64_t{0});
  r.revisits = j.value("revisits", std::int64_t{0});
  r.log_dir = j.at("log_dir").get<std::string>();
  r.wall_seconds = j.at("wall_seconds").get<double>();
  r.run_seconds = j.at("run_seconds").get<double>();
  r.peak_rss_kb = j.at("peak_rss_kb").get<std::map<std::string, long>>();
  r.log_bytes = j.at("log_bytes").get<std::uintmax_t>();
  const json& e = j.at("extrinsic");
  r.extrinsic.scenario = e.at("scenario").get<std::string>();
  r.extrinsic.success = e.at("success").get<bool>();
  r.extrinsic.completion = e.at("completion").get<int>();
  r.extrinsic.attempts = e.at("attempts").get<int>();
  r.extrinsic.utility = e.at("utility").get<double>();
  for (const auto& g : e.at("sub_goals"))
    r.extrinsic.sub_goals.push_back({g.at("x").get<double>(), g.at("y").get<double>(), g.at("iterations").get<int>(),
                                     g.at("actions_checked").get<int>(), g.at("actions_taken").get<int>(),
                                     g.at("reached").get<bool>()});
  return r;
}

// A finished run's outcome, kept as it finishes: --resume does not run it again.
void keepOutcome(const fs::path& out, const std::string& run_id, const RunOutcome& r) {
  fs::create_directories(out / "runs");
  writeWhole(outcomePath(out, run_id), json{{"run_id", run_id}, {"outcome", outcomeToJson(r)}}.dump() + "\n");
}

std::optional<RunOutcome> keptOutcome(const fs::path& out, const std::string& run_id) {
  const fs::path path = outcomePath(out, run_id);
  if (!fs::exists(path)) return std::nullopt;
  try {
    std::ifstream in(path);
    const json j = json::parse(in);
    if (j.at("run_id") != run_id) throw std::runtime_error("it is the outcome of run '" + j["run_id"].dump() + "'");
    return outcomeFromJson(j.at("outcome"));
  } catch (const std::exception& e) {
    throw ConfigError("cannot read " + path.string() + ": " + e.what());
  }
}

}  // namespace afford
