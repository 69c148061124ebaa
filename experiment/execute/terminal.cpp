#include "experiment/execute/terminal.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstring>

#include "afford/logging.hpp"

namespace afford {

namespace {
// In the pipe, between the program's own bytes: a board is kBoard, its lines (each ending in '\n'), kBoardEnd;
// kEnd ends the stream. (Control characters no text the program prints holds.)
constexpr char kBoard = '\x1e', kBoardEnd = '\x1f', kEnd = '\x1c';

void writeAll(int fd, const char* p, std::size_t n) {
  while (n > 0) {
    const ssize_t w = write(fd, p, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return;
    p += w;
    n -= static_cast<std::size_t>(w);
  }
}
}  // namespace

// The relay: a forked copy of the program that calls nothing but system calls
// (the other threads' locks stay locked in it), on memory made before the fork.
struct TerminalRelay::Screen {
  static constexpr std::size_t kMost = 32768;  // a board's bytes at most (more are dropped)
  int in = -1, tty = -1;
  char board[kMost];     // the board to draw: lines ending in '\n'
  std::size_t board_size = 0;
  char next[kMost];      // a board coming in
  std::size_t next_size = 0;
  bool receiving = false, fresh = false, ended = false;
  int drawn = 0;          // the board's rows on the screen, right above the cursor (0: none)
  bool line_start = true; // the text printed so far ends its line
  char buf[8192];

  void put(const char* p, std::size_t n) { writeAll(tty, p, n); }

  // Up to the board's first row, then clear below it.
  void erase() {
    if (drawn == 0) return;
    char seq[32] = "\x1b[";
    std::size_t k = 2;
    char digits[12];
    int d = 0;
    for (int v = drawn; v > 0; v /= 10) digits[d++] = static_cast<char>('0' + v % 10);
    while (d > 0) seq[k++] = digits[--d];
    std::memcpy(seq + k, "F\x1b[J", 4);
    put(seq, k + 4);
    drawn = 0;
  }

  void text(const char* p, std::size_t n) {
    if (n == 0) return;
    erase();
    put(p, n);
    line_start = p[n - 1] == '\n';
  }

  // The board below the text, each line cut to the terminal's width (a wrapped line would be a row the
  // erase does not count), and no more rows than the screen has.
  void draw() {
    if (!line_start || board_size == 0 || (drawn > 0 && !fresh)) return;
    erase();
    winsize ws{};
    const bool sized = ioctl(tty, TIOCGWINSZ, &ws) == 0 && ws.ws_col > 1 && ws.ws_row > 1;
    int rows = 0;
    for (std::size_t from = 0; from < board_size;) {
      if (sized && rows >= ws.ws_row - 1) break;
      const char* line = board + from;
      const char* end = static_cast<const char*>(std::memchr(line, '\n', board_size - from));
      const std::size_t size = static_cast<std::size_t>(end - line);
      std::size_t cut = size, columns = 0;
      if (sized)
        for (cut = 0; cut < size; ++cut) {  // a column per character: UTF-8's continuation bytes take none
          if ((static_cast<unsigned char>(line[cut]) & 0xC0) == 0x80) continue;
          if (++columns >= ws.ws_col) break;
        }
      put(line, cut);
      put("\n", 1);
      ++rows;
      from += size + 1;
    }
    drawn = rows;
    fresh = false;
  }

  // Bytes from the pipe: the program's text, boards, the end.
  void take(const char* p, std::size_t n) {
    for (std::size_t i = 0; i < n && !ended;) {
      if (receiving) {
        const char* stop = static_cast<const char*>(std::memchr(p + i, kBoardEnd, n - i));
        const std::size_t size = stop ? static_cast<std::size_t>(stop - (p + i)) : n - i;
        const std::size_t room = kMost - next_size;
        std::memcpy(next + next_size, p + i, size < room ? size : room);
        next_size += size < room ? size : room;
        i += size;
        if (!stop) continue;
        ++i;
        receiving = false;
        if (next_size > 0 && next[next_size - 1] != '\n') next[next_size - 1] = '\n';  // cut short: still lines
        std::memcpy(board, next, next_size);
        board_size = next_size;
        fresh = true;
        continue;
      }
      std::size_t j = i;
      while (j < n && p[j] != kBoard && p[j] != kEnd) ++j;
      text(p + i, j - i);
      if (j < n) {
        receiving = p[j] == kBoard;
        ended = p[j] == kEnd;
        next_size = 0;
        ++j;
      }
      i = j;
    }
  }

  void run() {
    for (;;) {
      const ssize_t r = read(in, buf, sizeof buf);
      if (r < 0 && errno == EINTR) continue;
      if (r <= 0) break;
      take(buf, static_cast<std::size_t>(r));
      if (ended) break;
      pollfd more{in, POLLIN, 0};
      if (poll(&more, 1, 0) > 0) continue;  // more to print first: the board once, after it
      draw();
    }
    // The end (or the program gone): the board's last drawing stays, below everything printed.
    if (!line_start) {
      put("\n", 1);
      line_start = true;
    }
    draw();
  }
};

namespace {

[[noreturn]] void relayMain(TerminalRelay::Screen& s) {
  prctl(PR_SET_NAME, "afford tty");  // its name in ps and top
  struct sigaction ignore {};
  ignore.sa_handler = SIG_IGN;
  // The terminal's Ctrl-C, and a signal to the program's group, stop the program: the relay prints its last words.
  for (int sig : {SIGINT, SIGTERM, SIGQUIT, SIGHUP, SIGPIPE}) sigaction(sig, &ignore, nullptr);
  // No other file of the program's stays open here (a lock, a socket).
  const int low = s.in < s.tty ? s.in : s.tty, high = s.in < s.tty ? s.tty : s.in;
  if (low > 3) close_range(3, static_cast<unsigned>(low - 1), 0);
  if (high > low + 1) close_range(static_cast<unsigned>(low + 1), static_cast<unsigned>(high - 1), 0);
  close_range(static_cast<unsigned>(high + 1), ~0U, 0);
  s.run();
  _exit(0);
}

// The same terminal (or file) as `tty`.
bool sameFile(int fd, int tty) {
  struct stat a {}, b {};
  if (fstat(fd, &a) != 0 || fstat(tty, &b) != 0) return false;
  if (S_ISCHR(a.st_mode) && S_ISCHR(b.st_mode)) return a.st_rdev == b.st_rdev;
  return a.st_dev == b.st_dev && a.st_ino == b.st_ino;
}

}  // namespace

TerminalRelay::TerminalRelay(std::FILE* out) : out_(out), screen_(std::make_unique<Screen>()) {
  const int fd = fileno(out);
  std::fflush(stdout);
  std::fflush(out);
  int ends[2] = {-1, -1};
  tty_ = fcntl(fd, F_DUPFD_CLOEXEC, 3);
  if (tty_ < 0) return;
  if (pipe2(ends, O_CLOEXEC) != 0 || ends[0] < 3 || ends[1] < 3) {  // (a standard descriptor closed: left alone)
    for (int end : ends)
      if (end >= 0) close(end);
    close(tty_);
    return;
  }
  screen_->in = ends[0];
  screen_->tty = tty_;
  const pid_t pid = fork();
  if (pid == 0) relayMain(*screen_);
  close(ends[0]);
  if (pid < 0) {
    close(ends[1]);
    close(tty_);
    return;
  }
  relay_ = pid;
  pipe_ = ends[1];
  for (int d : {fd, STDERR_FILENO, STDOUT_FILENO}) {
    if (saved_.count(d) || !sameFile(d, tty_)) continue;
    const int copy = fcntl(d, F_DUPFD_CLOEXEC, 3);
    if (copy < 0 || dup2(pipe_, d) < 0) {  // (left as it is: it could not be given back)
      if (copy >= 0) close(copy);
      continue;
    }
    saved_[d] = copy;
  }
  if (!saved_.count(fd)) {  // the board's own terminal not taken over: no relay
    finish();
    return;
  }
  // Standard output to a pipe would be written in blocks: line by line, as on the terminal.
  if (saved_.count(STDOUT_FILENO)) std::setvbuf(stdout, nullptr, _IOLBF, BUFSIZ);
}

TerminalRelay::~TerminalRelay() { finish(); }

void TerminalRelay::finish() {
  if (!started()) return;
  std::fflush(stdout);
  std::fflush(out_);
  for (const auto& [d, copy] : saved_) {
    dup2(copy, d);
    close(copy);
  }
  writeAll(pipe_, &kEnd, 1);
  close(pipe_);
  while (waitpid(relay_, nullptr, 0) < 0 && errno == EINTR) {
  }
  close(tty_);
  saved_.clear();
  relay_ = -1;
}

void TerminalRelay::show(const std::vector<std::string>& lines) {
  std::string record(1, kBoard);
  for (const std::string& line : lines) {
    for (char c : line)
      if (c != '\n' && c != kBoard && c != kBoardEnd && c != kEnd) record += c;
    record += '\n';
  }
  record += kBoardEnd;
  // Whole between two log lines' pieces (a console sink writes a line in several).
  std::lock_guard<std::mutex> lock(consoleMutex());
  writeAll(pipe_, record.data(), record.size());
}

}  // namespace afford
