// A run's outcome as the experiment keeps it: DIR/runs/<run-id>.json, written
// as the run finishes, so that an interrupted experiment does not run it
// again. Files are written whole or not at all.
#pragma once
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

#include "experiment/run/driver.hpp"

namespace afford {

// `text` into `path`, whole or not at all: written beside it, then renamed
// over it (an interruption leaves the previous version or the new one).
void writeWhole(const std::filesystem::path& path, const std::string& text);
// The same, streamed: what is written to out() goes to <path>.part, renamed over the path by commit(); a file
// never committed (an exception on the way) is removed. A long run's curves and summary are tens of
// megabytes: written as they are made, not built in memory first.
// `j` into `path` whole, as j.dump(indent) + "\n" writes it, streamed (a long run's summary is tens of MB).
void writeJsonWhole(const std::filesystem::path& path, const nlohmann::json& j, int indent = -1);
class WholeFile {
 public:
  explicit WholeFile(std::filesystem::path path);
  ~WholeFile();
  WholeFile(const WholeFile&) = delete;
  WholeFile& operator=(const WholeFile&) = delete;
  std::ostream& out() { return file_; }
  void commit();

 private:
  std::filesystem::path path_, part_;
  std::ofstream file_;
  bool committed_ = false;
};

// The outcome as JSON and back (its keys declared once: RunOutcome::visit); reading is strict, an error
// naming the key and `what`.
nlohmann::json outcomeToJson(const RunOutcome& r);
RunOutcome outcomeFromJson(const nlohmann::json& j, const std::string& what = "outcome");

// A JSON file, read only if it is a regular file of at most max_bytes (a FIFO would wait for a writer, a huge
// file hold the memory); throws std::runtime_error naming the file and what is wrong.
nlohmann::json readJsonFile(const std::filesystem::path& file, std::uintmax_t max_bytes);
// A small file's text, read only if it is a regular file of at most max_bytes (a FIFO would wait for a writer, a
// huge file hold the memory); throws std::runtime_error naming the file and what is wrong.
std::string smallFileText(const std::filesystem::path& file, std::uintmax_t max_bytes);
// The same for a small text file (a pid, a URL, a token) whose absence is no error: nullopt for any of those.
std::optional<std::string> readSmallFile(const std::filesystem::path& file, std::uintmax_t max_bytes);
// A log folder's manifest.json as readJsonFile reads it (at most 16 MiB, far above any logger's); a
// discarded value if it is not there or does not read.
nlohmann::json readManifest(const std::filesystem::path& file);
// The most a kept outcome of that run can take: its curve (a table every run.curve_interval steps of an
// intrinsic run, as the configuration says; every step if it cannot be read), far more than a table takes
// each, beside the rest. A larger file is no outcome of it (a million steps: 7.5 MB kept, 160 MiB allowed).
std::uintmax_t mostOutcomeBytes(const RunSpec& spec);

// A finished run's outcome, kept as it finishes: --resume does not run it again.
void keepOutcome(const std::filesystem::path& out, const std::string& run_id, const RunOutcome& r);
std::optional<RunOutcome> keptOutcome(const std::filesystem::path& out, const RunSpec& spec);

}  // namespace afford
