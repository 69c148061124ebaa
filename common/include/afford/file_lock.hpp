// A file held with a kernel lock (flock) while this object lives: what is in
// use says so, and the lock goes with its holder however the holder ends
// (SIGKILL included), so no later taker waits on, or is refused by, a dead
// one (docs/operating.md, "Locks").
#pragma once
#include <string>

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
  int fd() const { return fd_; }  // the descriptor holding it (-1: none)
  void release();

 private:
  int fd_ = -1;
};

// FILE.partial, being written by this process: created, or taken over from a writer that died before it
// finished (its lock is gone with it), emptied, and held until released. Throws std::runtime_error naming it
// if another writer holds it (`who`: what writes it, for the message).
void holdPartial(HeldFile& held, const std::string& partial, const std::string& who);

}  // namespace afford
