#include "experiment/run/outcome.hpp"

#include <iomanip>

#include <fstream>

#include <yaml-cpp/yaml.h>

#include <algorithm>

#include "afford/config.hpp"
#include "afford/version.hpp"
#include "experiment/schema/codec.hpp"

namespace afford {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {
fs::path outcomePath(const fs::path& out, const std::string& run_id) { return out / "runs" / (run_id + ".json"); }
}  // namespace

// `text` into `path`, whole or not at all: written beside it, then renamed
// over it (an interruption leaves the previous version or the new one).
void writeWhole(const fs::path& path, const std::string& text) {
  WholeFile f(path);
  f.out() << text;
  f.commit();
}

void writeJsonWhole(const fs::path& path, const json& j, int indent) {
  WholeFile f(path);
  if (indent >= 0) f.out() << std::setw(indent);
  f.out() << j << "\n";
  f.commit();
}

WholeFile::WholeFile(fs::path path)
    : path_(std::move(path)), part_(path_.string() + ".part"), file_(part_, std::ios::binary | std::ios::trunc) {}

WholeFile::~WholeFile() {
  if (committed_) return;
  file_.close();
  std::error_code ec;
  fs::remove(part_, ec);
}

void WholeFile::commit() {
  file_.close();
  if (!file_) throw std::runtime_error("cannot write " + part_.string());
  fs::rename(part_, path_);
  committed_ = true;
}

json outcomeToJson(const RunOutcome& r) { return toJsonOf(r); }

RunOutcome outcomeFromJson(const json& j, const std::string& what) { return fromJsonOf<RunOutcome>(j, what); }

// A finished run's outcome, kept as it finishes: --resume does not run it again.
void keepOutcome(const fs::path& out, const std::string& run_id, const RunOutcome& r) {
  fs::create_directories(out / "runs");
  writeJsonWhole(outcomePath(out, run_id),
                 json{{"run_id", run_id}, {"outcome", outcomeToJson(r)}, {"afford_version", affordVersion()}});
}

std::uintmax_t mostOutcomeBytes(const RunSpec& spec) {
  constexpr std::uintmax_t kRest = 4u << 20;         // everything but the curve
  constexpr std::uintmax_t kTableBytes = 16u << 10;  // a curve point's table (about 750 bytes kept)
  std::int64_t interval = 1;
  try {
    const YAML::Node run = YAML::Load(spec.config_yaml)["run"];
    if (run && run["curve_interval"]) interval = std::max<std::int64_t>(1, run["curve_interval"].as<std::int64_t>());
  } catch (const std::exception&) {
    // unreadable: a table at every step
  }
  const std::int64_t points = spec.extrinsic ? 0 : std::max<std::int64_t>(0, spec.steps) / interval + 2;
  return kRest + static_cast<std::uintmax_t>(points) * kTableBytes;
}

std::optional<RunOutcome> keptOutcome(const fs::path& out, const RunSpec& spec) {
  const std::string& run_id = spec.run_id;
  const fs::path path = outcomePath(out, run_id);
  std::error_code ec;
  if (!fs::exists(path, ec)) return std::nullopt;
  try {
    const json j = readJsonFile(path, mostOutcomeBytes(spec));
    if (!j.is_object() || !j.contains("run_id") || j["run_id"] != run_id)
      throw std::runtime_error("it is not the outcome of run '" + run_id + "'");
    // afford_version: the build that wrote it (from 0.2.0; 0.1.0 wrote the other two alone).
    const bool versioned = j.contains("afford_version") && j["afford_version"].is_string();
    if (j.size() != 2u + versioned || !j.contains("outcome"))
      throw std::runtime_error("expected the keys run_id, outcome and afford_version");
    return outcomeFromJson(j.at("outcome"), path.string() + ": outcome");
  } catch (const std::exception& e) {
    throw ConfigError("cannot read " + path.string() + ": " + e.what());
  }
}

std::optional<std::string> readSmallFile(const fs::path& file, std::uintmax_t max_bytes) {
  try {
    return smallFileText(file, max_bytes);
  } catch (const std::runtime_error&) {
    return std::nullopt;
  }
}

json readManifest(const fs::path& file) {
  try {
    return readJsonFile(file, 16u << 20);
  } catch (const std::exception&) {
    return json(json::value_t::discarded);
  }
}

std::string smallFileText(const fs::path& file, std::uintmax_t max_bytes) {
  // Checked before it is opened: a FIFO would wait for a writer, a huge file hold the memory.
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) throw std::runtime_error(file.string() + ": not a regular file");
  const std::uintmax_t size = fs::file_size(file, ec);
  if (ec) throw std::runtime_error(file.string() + ": cannot read its size (" + ec.message() + ")");
  if (size > max_bytes)
    throw std::runtime_error(file.string() + ": " + std::to_string(size) + " bytes, more than such a file holds (at most " +
                             std::to_string(max_bytes) + ")");
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": cannot be read");
  return std::string(std::istreambuf_iterator<char>(in), {});
}

json readJsonFile(const fs::path& file, std::uintmax_t max_bytes) {
  const std::string text = smallFileText(file, max_bytes);
  try {
    return json::parse(text);
  } catch (const json::parse_error& e) {
    throw std::runtime_error(file.string() + ": not JSON (" + e.what() + ")");
  }
}

}  // namespace afford
