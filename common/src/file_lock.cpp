#include "afford/file_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace afford {

bool HeldFile::take(const std::string& path, Mode mode, int open_flags, bool wait) {
  release();
  const int fd = ::open(path.c_str(), open_flags | O_CLOEXEC, 0644);
  if (fd < 0) return false;
  const int op = (mode == Mode::Exclusive ? LOCK_EX : LOCK_SH) | (wait ? 0 : LOCK_NB);
  while (::flock(fd, op) != 0) {
    if (wait && errno == EINTR) continue;
    const int err = errno;
    ::close(fd);
    errno = err;
    return false;
  }
  fd_ = fd;
  return true;
}

bool HeldFile::tryHold(const std::string& path, Mode mode, int open_flags) { return take(path, mode, open_flags, false); }
bool HeldFile::hold(const std::string& path, Mode mode, int open_flags) { return take(path, mode, open_flags, true); }

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

void prepareOutput(const std::filesystem::path& file, const std::string& option,
                   const std::vector<std::string>& extensions) {
  namespace fs = std::filesystem;
  const std::string named = option + " " + file.string();
  if (file.empty() || !file.has_filename()) throw std::runtime_error(named + ": names no file");
  if (!extensions.empty()) {
    std::string ext = file.extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    bool known = false;
    std::string list;
    for (const std::string& e : extensions) {
      known = known || ext == e;
      list += (list.empty() ? "" : &e == &extensions.back() ? " or " : ", ") + e;
    }
    if (!known) throw std::runtime_error(named + ": the name must end in " + list);
  }
  std::error_code ec;
  if (fs::is_directory(file, ec)) throw std::runtime_error(named + ": is a folder, not a file");
  const fs::path folder = file.parent_path();
  if (folder.empty() || fs::is_directory(folder, ec)) return;
  fs::create_directories(folder, ec);
  if (ec || !fs::is_directory(folder))
    throw std::runtime_error(named + ": cannot make its folder " + folder.string() + ": " +
                             (ec ? ec.message() : "a file is in the way"));
}

}  // namespace afford
