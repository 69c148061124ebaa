// A group of afford processes started by the runner (one per process name),
// each with its output in a file, watched for unexpected exits, and stopped
// with SIGTERM then SIGKILL after a grace period. Each child leads a process
// group of its own, so a signal from the terminal reaches the runner only.
#pragma once
#include <sys/types.h>

#include <map>
#include <string>
#include <vector>

namespace afford {

// CPU priority (nice) of the processes that only watch a run: the logger and
// the runner's bus thread. With every datagram waking every listener on the
// run's port, keeping watchers from preempting the agent's processes shortens
// each step.
inline constexpr int kWatcherNice = 10;

struct Child {
  std::string name;   // "eye"
  pid_t pid = -1;
  std::string output; // file with its stdout and stderr
  std::string command; // the command it runs in place of afford-<name> ("" for the shipped one)
  bool exited = false;
  int status = 0;
};

class ProcessGroup {
 public:
  // Starts build/bin/afford-<name> --lcm-url URL [common_args...] [args[name]...] for each name; a name
  // that `commands` gives a shell command starts that instead, with the same arguments appended
  // (/bin/sh -c 'exec CMD "$@"', so the child is the command itself).
  ProcessGroup(const std::string& bin_dir, const std::vector<std::string>& names, const std::string& lcm_url,
               const std::string& output_dir, const std::vector<std::string>& common_args = {},
               const std::map<std::string, std::vector<std::string>>& args = {},
               const std::map<std::string, std::string>& commands = {});
  ~ProcessGroup();
  ProcessGroup(const ProcessGroup&) = delete;
  ProcessGroup& operator=(const ProcessGroup&) = delete;

  // "" while every child runs; otherwise which one ended, and how.
  std::string health();
  // SIGTERM, wait up to `grace_ms`, then SIGKILL.
  void stop(int grace_ms = 3000);
  const std::vector<Child>& children() const { return children_; }
  // Peak resident memory (VmHWM, kB) of each running child.
  std::map<std::string, long> peakRssKb() const;

 private:
  std::vector<Child> children_;
};

// Peak resident memory (VmHWM, kB) of a process, or -1.
long peakRssKb(pid_t pid);

// Where the process executables (afford-<name>) and the runner (afford) live:
// the running executable's folder, or the one a host that is not the afford
// executable (the Python package) set.
std::string executableDir();
// FNV-1a of the executables (afford and every afford-<process>): another build is other code.
const std::string& codeFingerprint();
void setExecutableDir(const std::string& dir);

}  // namespace afford
