// afford clean: the folders of a log root (run logs and checkpoints, stored
// agents) chosen by age, size or experiment; a dry run unless --delete.
#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>

#include "afford/commands.hpp"
#include "afford/config.hpp"

namespace afford {
namespace fs = std::filesystem;

namespace {

struct Entry {
  fs::path path;
  std::string label;       // run id, or agents/<key>
  std::string experiment;  // "?" if nothing in the folder says
  std::uintmax_t bytes = 0;
  std::time_t modified = 0;  // the newest file in it
};

std::string experimentOf(const fs::path& dir) {
  for (const char* name : {"run.json", "manifest.json", "outcome.json"}) {
    std::ifstream in(dir / name);
    if (!in) continue;
    try {
      const auto j = nlohmann::json::parse(in);
      if (j.contains("experiment") && j["experiment"].is_string()) return j["experiment"].get<std::string>();
    } catch (const std::exception&) {
      // an unreadable file says nothing about the folder; the next one may
    }
  }
  return "?";
}

Entry measure(const fs::path& dir, const std::string& label) {
  Entry e{dir, label, experimentOf(dir)};
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    struct stat st {};
    if (stat(it->path().c_str(), &st) != 0) continue;
    // A file linked from several folders (a run's checkpoint and its stored agent) counts a share in each.
    if (S_ISREG(st.st_mode)) e.bytes += static_cast<std::uintmax_t>(st.st_size) / std::max<nlink_t>(st.st_nlink, 1);
    e.modified = std::max(e.modified, st.st_mtime);
  }
  return e;
}

}  // namespace

Command cleanCommand(CLI::App& app, const FrontDoor&) {
  struct Args {
    std::string log_root = "logs";
    std::vector<std::string> experiments;
    double older_than_days = -1, larger_than_mb = -1, keep_under_mb = -1;
    bool all = false, remove = false;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand("clean", "list, then with --delete remove, the run folders and stored agents of a log "
                                          "root chosen by age, size or experiment (a dry run by default)");
  cmd->add_option("--log-root", a->log_root, "the log root (an experiment's --log-root)")->capture_default_str();
  cmd->add_option("--older-than", a->older_than_days, "folders last changed more than this many days ago")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--larger-than", a->larger_than_mb, "folders of more than this many MB")->check(CLI::NonNegativeNumber);
  cmd->add_option("--experiment", a->experiments, "folders of these experiments (repeatable)");
  cmd->add_option("--keep-under", a->keep_under_mb,
                  "the oldest folders, until what is left takes at most this many MB")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--all", a->all, "every folder");
  cmd->add_flag("--delete", a->remove, "remove them (without it, only list what would go)");
  return {cmd, [a] {
            if (!a->all && a->older_than_days < 0 && a->larger_than_mb < 0 && a->experiments.empty() &&
                a->keep_under_mb < 0)
              throw ConfigError("afford clean: choose folders with --older-than, --larger-than, --experiment, "
                                "--keep-under or --all");
            if (!fs::is_directory(a->log_root)) throw ConfigError("afford clean: no log root " + a->log_root);
            std::vector<Entry> entries;
            for (const auto& d : fs::directory_iterator(a->log_root)) {
              if (!d.is_directory()) continue;
              const std::string name = d.path().filename().string();
              if (name == "agents") {
                for (const auto& k : fs::directory_iterator(d.path()))
                  if (k.is_directory()) entries.push_back(measure(k.path(), "agents/" + k.path().filename().string()));
              } else {
                entries.push_back(measure(d.path(), name));
              }
            }
            std::sort(entries.begin(), entries.end(), [](const Entry& x, const Entry& y) {
              return x.modified != y.modified ? x.modified < y.modified : x.label < y.label;
            });
            const std::time_t now = std::time(nullptr);
            std::uintmax_t total = 0;
            for (const auto& e : entries) total += e.bytes;
            std::vector<const Entry*> chosen;
            std::uintmax_t left = total;
            for (const auto& e : entries) {
              bool pick = a->all;
              if (a->older_than_days >= 0) pick = pick || difftime(now, e.modified) > a->older_than_days * 86400.0;
              if (a->larger_than_mb >= 0) pick = pick || e.bytes > a->larger_than_mb * 1e6;
              if (!a->experiments.empty())
                pick = pick || std::find(a->experiments.begin(), a->experiments.end(), e.experiment) != a->experiments.end();
              if (a->keep_under_mb >= 0) pick = pick || left > a->keep_under_mb * 1e6;  // oldest first
              if (!pick) continue;
              chosen.push_back(&e);
              left -= e.bytes;
            }
            std::uintmax_t freed = 0;
            for (const Entry* e : chosen) {
              char when[32];
              std::strftime(when, sizeof when, "%Y-%m-%d %H:%M", std::localtime(&e->modified));
              std::printf("%s %10.1f MB  %s  %-16s %s\n", a->remove ? "removed" : "would remove", e->bytes / 1e6, when,
                          e->experiment.c_str(), e->path.string().c_str());
              if (a->remove) fs::remove_all(e->path);
              freed += e->bytes;
            }
            if (a->remove && fs::is_directory(fs::path(a->log_root) / "agents") &&
                fs::is_empty(fs::path(a->log_root) / "agents"))
              fs::remove(fs::path(a->log_root) / "agents");
            std::printf("%s %zu of %zu folder(s), %.1f MB of %.1f MB in %s%s\n", a->remove ? "removed" : "would remove",
                        chosen.size(), entries.size(), freed / 1e6, total / 1e6, a->log_root.c_str(),
                        a->remove || chosen.empty() ? "" : " (a dry run: --delete removes them)");
            return 0;
          }};
}

}  // namespace afford
