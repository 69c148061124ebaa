#include "experiment/run/group.hpp"
#include "afford/checksum.hpp"
#include "afford/processes.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <thread>
#include <vector>

namespace afford {

namespace {
std::string& givenExecutableDir() {
  static std::string dir;
  return dir;
}
}  // namespace

void setExecutableDir(const std::string& dir) { givenExecutableDir() = dir; }

std::string executableDir() {
  if (!givenExecutableDir().empty()) return givenExecutableDir();
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot locate the afford executable: " + ec.message());
  return exe.parent_path().string();
}

ProcessGroup::ProcessGroup(const std::string& bin_dir, const std::vector<std::string>& names, const std::string& lcm_url,
                           const std::string& output_dir, const std::vector<std::string>& common_args,
                           const std::map<std::string, std::vector<std::string>>& own_args,
                           const std::map<std::string, std::string>& commands) {
  std::filesystem::create_directories(output_dir);
  for (const auto& name : names) {
    Child c;
    c.name = name;
    c.output = (std::filesystem::path(output_dir) / (name + ".log")).string();
    if (const auto it = commands.find(name); it != commands.end()) c.command = it->second;
    const std::string exe = (std::filesystem::path(bin_dir) / ("afford-" + name)).string();
    const auto command = commands.find(name);
    if (command == commands.end() && access(exe.c_str(), X_OK) != 0) {
      stop(0);
      throw std::runtime_error("process executable " + exe + " is missing (build it: cmake --build build)");
    }
    // A swapped process: the shell runs the command with the standard arguments as "$@" (its $0 names the
    // process it stands for, in the shell's own errors).
    std::vector<std::string> args = command == commands.end()
                                        ? std::vector<std::string>{exe}
                                        : std::vector<std::string>{"/bin/sh", "-c", "exec " + command->second + " \"$@\"",
                                                                   "afford-" + name};
    args.insert(args.end(), {"--lcm-url", lcm_url});
    args.insert(args.end(), common_args.begin(), common_args.end());
    if (const auto it = own_args.find(name); it != own_args.end()) args.insert(args.end(), it->second.begin(), it->second.end());
    const pid_t parent = getpid();
    const pid_t pid = fork();
    if (pid < 0) {
      stop(0);
      throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
    }
    if (pid == 0) {
      prctl(PR_SET_PDEATHSIG, SIGTERM);  // never outlive the runner
      // A process group of its own: the terminal's Ctrl-C goes to the runner
      // alone, which stops the run in order and then ends the group.
      setpgid(0, 0);
      // The logger only records: a lower CPU priority keeps its wake-ups from
      // preempting the processes on the step's critical path (its socket
      // buffer holds far more than it ever falls behind).
      // (The agent's processes get back the default priority, whatever the
      // runner's thread has.)
      setpriority(PRIO_PROCESS, 0, name == "logger" ? kWatcherNice : 0);
      if (getppid() != parent) _exit(1);
      const int null = open("/dev/null", O_RDONLY);  // never read the terminal from the background
      if (null >= 0) {
        dup2(null, 0);
        close(null);
      }
      const int fd = open(c.output.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
      if (fd >= 0) {
        dup2(fd, 1);
        dup2(fd, 2);
        close(fd);
      }
      std::vector<char*> argv;
      for (auto& a : args) argv.push_back(a.data());
      argv.push_back(nullptr);
      execv(argv[0], argv.data());
      _exit(127);
    }
    setpgid(pid, pid);  // also here: the group exists whichever of the two runs first
    c.pid = pid;
    children_.push_back(c);
  }
}

ProcessGroup::~ProcessGroup() { stop(); }

namespace {
// The child's whole process group (it leads one): a swapped command may have started processes of its own.
void signalChild(pid_t pid, int sig) {
  if (kill(-pid, sig) != 0) kill(pid, sig);
}
}  // namespace

long peakRssKb(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("VmHWM:", 0) == 0) return std::stol(line.substr(6));
  return -1;
}

std::map<std::string, long> ProcessGroup::peakRssKb() const {
  std::map<std::string, long> out;
  for (const auto& c : children_)
    if (!c.exited) out[c.name] = afford::peakRssKb(c.pid);
  return out;
}

std::string ProcessGroup::health() {
  for (auto& c : children_) {
    if (c.exited) continue;
    int status = 0;
    if (waitpid(c.pid, &status, WNOHANG) == c.pid) {
      c.exited = true;
      c.status = status;
      std::string how = WIFEXITED(status)     ? "exited with status " + std::to_string(WEXITSTATUS(status))
                        : WIFSIGNALED(status) ? "was killed by signal " + std::to_string(WTERMSIG(status)) + " (SIG" +
                                                    sigabbrev_np(WTERMSIG(status)) + ")"
                                              : "ended";
      return "process '" + c.name + "' (pid " + std::to_string(c.pid) + (c.command.empty() ? "" : ", command '" + c.command + "'") +
             ") " + how + "; its output: " + c.output;
    }
  }
  for (const auto& c : children_)
    if (c.exited) return "process '" + c.name + "' (pid " + std::to_string(c.pid) + ") is not running";
  return "";
}

void ProcessGroup::stop(int grace_ms) {
  for (auto& c : children_)
    if (!c.exited) signalChild(c.pid, SIGTERM);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(grace_ms);
  for (auto& c : children_) {
    while (!c.exited) {
      int status = 0;
      const pid_t r = waitpid(c.pid, &status, WNOHANG);
      if (r == c.pid || r < 0) {
        c.exited = true;
        c.status = status;
        break;
      }
      if (std::chrono::steady_clock::now() >= deadline) {
        signalChild(c.pid, SIGKILL);
        waitpid(c.pid, &status, 0);
        c.exited = true;
        c.status = status;
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
}

const std::string& codeFingerprint() {
  static const std::string fingerprint = [] {
    Fnv1a h;
    const std::filesystem::path bin = executableDir();
    std::vector<std::filesystem::path> files{bin / "afford"};  // the runner (the one running, unless another host set the folder)
    for (const ProcessInfo& p : processRegistry()) files.push_back(bin / ("afford-" + std::string(p.name)));
    std::vector<char> buf(1 << 20);
    for (const auto& f : files) {
      std::ifstream in(f, std::ios::binary);
      while (in.read(buf.data(), static_cast<std::streamsize>(buf.size())) || in.gcount() > 0)
        h.add(buf.data(), static_cast<std::size_t>(in.gcount()));
    }
    return h.hex();
  }();
  return fingerprint;
}

}  // namespace afford
