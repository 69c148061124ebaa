#include "afford/file_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace afford {

bool HeldFile::tryHold(const std::string& path, Mode mode, int open_flags) {
  release();
  const int fd = ::open(path.c_str(), open_flags | O_CLOEXEC, 0644);
  if (fd < 0) return false;
  if (::flock(fd, (mode == Mode::Exclusive ? LOCK_EX : LOCK_SH) | LOCK_NB) != 0) {
    const int err = errno;
    ::close(fd);
    errno = err;
    return false;
  }
  fd_ = fd;
  return true;
}

void HeldFile::release() {
  if (fd_ >= 0) ::close(fd_);  // (which lets go of the lock)
  fd_ = -1;
}

void holdPartial(HeldFile& held, const std::string& partial, const std::string& who) {
  if (!held.tryHold(partial, HeldFile::Mode::Exclusive, O_WRONLY | O_CREAT)) {
    const int err = errno;
    throw std::runtime_error(err == EWOULDBLOCK ? partial + " is being written by another " + who + " (it holds its lock)"
                                                : "cannot create " + partial + ": " + std::strerror(err));
  }
  // Ours now: a file of a writer that died is what it left half-written.
  if (::ftruncate(held.fd(), 0) != 0) {
    const int err = errno;
    held.release();
    throw std::runtime_error("cannot empty " + partial + ": " + std::strerror(err));
  }
}

}  // namespace afford
