// A file held with a kernel lock (flock) while this object lives: what is in
// use says so, and the lock goes with its holder however the holder ends
// (SIGKILL included), so no later taker waits on, or is refused by, a dead
// one (docs/operating.md, "Locks"). And the check every output file of a
// command has before any work: its name, and its folder.
#pragma once
#include <filesystem>
#include <string>
#include <vector>

namespace afford {

class HeldFile {
 public:
  enum class Mode { Exclusive, Shared };
  HeldFile() = default;
  ~HeldFile() { release(); }
  HeldFile(const HeldFile&) = delete;
  HeldFile& operator=(const HeldFile&) = delete;

  // Opens `path` with `open_flags` (O_CREAT with mode 0644 if given) and takes its lock without waiting:
  // false if another holder has it (or the file cannot be opened: errno says which).
  bool tryHold(const std::string& path, Mode mode, int open_flags);
  // The same, waiting for the lock until the holder lets go (or dies): false only if the file cannot be opened.
  bool hold(const std::string& path, Mode mode, int open_flags);
  int fd() const { return fd_; }  // the descriptor holding it (-1: none)
  void release();

 private:
  bool take(const std::string& path, Mode mode, int open_flags, bool wait);
  int fd_ = -1;
};

// FILE.partial, being written by this process: created, or taken over from a writer that died before it
// finished (its lock is gone with it), emptied, and held until released. Throws std::runtime_error naming it
// if another writer holds it (`who`: what writes it, for the message).
void holdPartial(HeldFile& held, const std::string& partial, const std::string& who);

// A file a command is to write, before any work (`option`: how the command line names it, for the messages):
// its name must end in one of `extensions` (any case; none given: any name), and its folder is made if it is
// missing, as every output folder of afford is. Throws std::runtime_error naming the option and the file, and
// the folder when it cannot be made.
void prepareOutput(const std::filesystem::path& file, const std::string& option,
                   const std::vector<std::string>& extensions = {});

}  // namespace afford
