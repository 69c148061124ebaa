#include "experiment/execute/run_folder.hpp"

#include <fcntl.h>
#include <stdio.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <optional>

#include <nlohmann/json.hpp>

#include "afford/config.hpp"
#include "afford/version.hpp"
#include "experiment/run/outcome.hpp"

namespace afford {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::optional<json> smallJson(const fs::path& file) {
  try {
    return readJsonFile(file, 1u << 20);
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

std::string stringAt(const json& j, const char* key) {
  return j.is_object() && j.contains(key) && j[key].is_string() ? j[key].get<std::string>() : std::string();
}

// The experiment folder a run.json names, as one path for every spelling of it.
std::string sameFolder(const std::string& dir) {
  std::error_code ec;
  return dir.empty() ? dir : fs::weakly_canonical(fs::absolute(dir), ec).string();
}

// "" if the folder is the experiment's of out_dir (its run.json says so), else whose it is.
std::string notOurs(const fs::path& run_dir, const std::string& out_dir) {
  const auto note = smallJson(run_dir / "run.json");
  if (note && sameFolder(stringAt(*note, "out_dir")) == sameFolder(out_dir)) return "";
  return runFolderHolder(run_dir);
}

// Makes the run's folder with its run.json in it, at once: "" once done, else why not (the folder exists, or
// cannot be made). The folder is made aside (.<run-id>.claim-<pid>) with its run.json, then renamed into place
// unless something is there already (RENAME_NOREPLACE): another claimant never sees it without its run.json.
std::string claim(const fs::path& run_dir, const PlannedRun& run, const std::string& out_dir) {
  std::error_code ec;
  fs::create_directories(run_dir.parent_path(), ec);
  if (ec) return "cannot make the log folder " + run_dir.string() + " (" + ec.message() + ")";
  if (fs::exists(run_dir, ec)) return "the log folder " + run_dir.string() + " exists already: " + runFolderHolder(run_dir);
  const fs::path aside = run_dir.parent_path() / ("." + run_dir.filename().string() + ".claim-" + std::to_string(getpid()));
  fs::remove_all(aside, ec);  // (one this very pid left: a pid is not reused while it lives)
  if (!fs::create_directory(aside, ec) || ec)
    return "cannot make the log folder " + run_dir.string() + " (" + (ec ? ec.message() : "exists") + ")";
  try {
    writeWhole(aside / "run.json",
               json{{"run_id", run.spec.run_id}, {"experiment", run.spec.experiment},
                    {"out_dir", fs::absolute(out_dir).string()}, {"afford_version", affordVersion()}}
                       .dump() + "\n");
  } catch (const std::exception& e) {
    fs::remove_all(aside, ec);
    return "cannot write " + (run_dir / "run.json").string() + " (" + e.what() + ")";
  }
  if (renameat2(AT_FDCWD, aside.c_str(), AT_FDCWD, run_dir.c_str(), RENAME_NOREPLACE) != 0) {
    const int err = errno;
    fs::remove_all(aside, ec);
    if (err == EEXIST) return "the log folder " + run_dir.string() + " exists already: " + runFolderHolder(run_dir);
    return "cannot make the log folder " + run_dir.string() + " (" + std::strerror(err) + ")";
  }
  return "";
}

// Why this process cannot write a file in `dir` ("" if it can): one byte written, synced and removed.
std::string writeProblem(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return dir.string() + ": " + ec.message();
  const fs::path probe = dir / (".write-test-" + std::to_string(getpid()));
  const int fd = open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) return dir.string() + ": " + std::strerror(errno);
  const bool written = write(fd, "x", 1) == 1 && fsync(fd) == 0;
  const int err = errno;
  close(fd);
  unlink(probe.c_str());
  return written ? "" : dir.string() + ": " + std::strerror(err);
}

}  // namespace

std::string runFolderHolder(const fs::path& run_dir) {
  if (const auto note = smallJson(run_dir / "run.json")) {
    const std::string out = stringAt(*note, "out_dir");
    return "run '" + stringAt(*note, "run_id") + "' of experiment " + stringAt(*note, "experiment") +
           (out.empty() ? std::string() : ", writing to " + out);
  }
  if (const auto manifest = smallJson(run_dir / "manifest.json"); manifest && !stringAt(*manifest, "experiment").empty())
    return "a log of experiment " + stringAt(*manifest, "experiment") + ", with no run.json saying whose";
  return "nothing in it says whose it is";
}

void refuseHeldRunFolders(const std::vector<const PlannedRun*>& runs, const std::string& log_root) {
  std::error_code ec;
  for (const PlannedRun* p : runs)
    if (const fs::path dir = fs::path(log_root) / p->spec.run_id; fs::exists(dir, ec))
      throw ConfigError("the log folder " + dir.string() + " exists already (" + runFolderHolder(dir) +
                        "): choose another --run-prefix or --log-root");
}

void claimRunFolders(std::vector<const PlannedRun*> runs, const std::string& log_root, const std::string& out_dir) {
  // One order for every claimant: of two experiments wanting the same folders, the one that has the first
  // contested folder gets them all.
  std::sort(runs.begin(), runs.end(),
            [](const PlannedRun* a, const PlannedRun* b) { return a->spec.run_id < b->spec.run_id; });
  std::vector<fs::path> made;
  for (const PlannedRun* p : runs) {
    const fs::path dir = fs::path(log_root) / p->spec.run_id;
    const std::string why = claim(dir, *p, out_dir);
    if (why.empty()) {
      made.push_back(dir);
      continue;
    }
    std::error_code ec;
    for (const fs::path& m : made) {  // (only what was made here: run.json and the empty folder)
      fs::remove(m / "run.json", ec);
      fs::remove(m, ec);
    }
    throw ConfigError(why + ": choose another --run-prefix or --log-root");
  }
}

void reclaimMovedRunFolders(const std::string& log_root, const std::string& was, const std::string& out_dir) {
  std::error_code ec;
  const std::string former = fs::path(was).lexically_normal().string();
  for (auto it = fs::directory_iterator(log_root, ec); !ec && it != fs::directory_iterator(); it.increment(ec)) {
    const fs::path note_file = it->path() / "run.json";
    auto note = smallJson(note_file);
    if (!note || fs::path(stringAt(*note, "out_dir")).lexically_normal().string() != former) continue;
    (*note)["out_dir"] = fs::absolute(out_dir).lexically_normal().string();
    (*note)["afford_version"] = affordVersion();
    writeWhole(note_file, note->dump() + "\n");
  }
}

std::string takeRunFolder(const fs::path& run_dir, const PlannedRun& run, const std::string& out_dir) {
  std::error_code ec;
  if (!fs::exists(run_dir, ec)) {
    const std::string why = claim(run_dir, run, out_dir);
    if (why.empty() || !fs::exists(run_dir, ec)) return why;
  }  // (made meanwhile: by whom?)
  if (const std::string whose = notOurs(run_dir, out_dir); !whose.empty())
    return "the log folder " + run_dir.string() + " is not this experiment's: " + whose;
  return "";
}

std::string anotherHolder(const fs::path& run_dir, const std::string& out_dir) {
  std::error_code ec;
  return fs::exists(run_dir / "run.json", ec) ? notOurs(run_dir, out_dir) : "";
}

bool onlyClaimed(const fs::path& run_dir, const std::string& out_dir) {
  std::error_code ec;
  int entries = 0;
  for (auto it = fs::directory_iterator(run_dir, ec); !ec && it != fs::directory_iterator(); it.increment(ec))
    if (++entries > 1 || it->path().filename() != "run.json") return false;
  return !ec && entries == 1 && notOurs(run_dir, out_dir).empty();
}

void releaseUnused(const fs::path& run_dir, const std::string& out_dir) {
  if (!onlyClaimed(run_dir, out_dir)) return;
  std::error_code ec;
  fs::remove(run_dir / "run.json", ec);
  fs::remove(run_dir, ec);  // (only if nothing came meanwhile)
}

std::string missingOutputs(const PlannedRun& run, const RunOutcome& r, const std::string& their_log) {
  std::vector<std::string> missing;
  std::error_code ec;
  if (!run.spec.extrinsic) {
    const std::string checkpoint = parseRunConfigText(run.spec.config_yaml).checkpoint;
    if (!checkpoint.empty() && (r.checkpoint.empty() || !fs::is_regular_file(r.checkpoint, ec))) {
      const std::string why = writeProblem(fs::path(checkpoint).parent_path());
      missing.push_back("its checkpoint " + checkpoint + " was not written (" +
                        (!why.empty() ? why
                         : r.checkpoint.empty()
                             ? "the predictors reported they could not write it; their log says why" +
                                   (their_log.empty() ? std::string() : ": " + their_log)
                             : "the predictors reported it written, and it is not there") +
                        ")");
    }
  }
  // (A logger whose --log-dir is not the runner's --log-root closes the log elsewhere: the run has no log folder.)
  if (run.keep_log && !r.log_dir.empty()) {
    bool segment = false;
    for (auto it = fs::directory_iterator(r.log_dir, ec); !ec && it != fs::directory_iterator(); it.increment(ec))
      segment = segment || it->path().extension() == ".lcm";
    if (!segment || !fs::is_regular_file(fs::path(r.log_dir) / "manifest.json", ec)) {
      const std::string why = writeProblem(r.log_dir);
      missing.push_back("its log in " + r.log_dir + " lacks " + (segment ? "its manifest.json" : "a log file") +
                        (why.empty() ? "" : " (" + why + ")"));
    }
  }
  std::string said;
  for (const std::string& m : missing) said += (said.empty() ? "" : "; ") + m;
  return said;
}

}  // namespace afford
