// The terminal while a progress board is on it. Whatever the program writes
// there (its standard error, and its standard output when that is the same
// terminal: log lines, a signal handler's words, a crash's) goes through a pipe
// to a relay process, the terminal's only writer, which prints it and draws the
// board again below it. So the board never moves up past a line it did not
// draw, and what the program said just before it died is printed all the same
// (the relay prints until the pipe closes).
#pragma once
#include <sys/types.h>

#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace afford {

class TerminalRelay {
 public:
  // Takes `out`'s terminal over; started() is false when that could not be done (nothing changed then).
  explicit TerminalRelay(std::FILE* out);
  // Gives the terminal back once the relay has printed all it was given; the board's last drawing stays.
  ~TerminalRelay();
  TerminalRelay(const TerminalRelay&) = delete;
  TerminalRelay& operator=(const TerminalRelay&) = delete;

  bool started() const { return relay_ > 0; }
  // The board, a line each, as the relay draws it from now on (below every line printed so far).
  void show(const std::vector<std::string>& lines);

  struct Screen;  // the relay's side (terminal.cpp)

 private:
  void finish();  // the terminal given back, once the relay has printed all it was given

  std::FILE* out_;
  int tty_ = -1, pipe_ = -1;          // the terminal (a copy of out's descriptor) and the pipe's end we write
  pid_t relay_ = -1;
  std::map<int, int> saved_;          // each descriptor sent to the pipe, and a copy of what it was
  std::unique_ptr<Screen> screen_;    // the relay's memory, made before the fork (the relay allocates nothing)
};

}  // namespace afford
