"""A command on a pseudo-terminal, and what its screen shows at the end.

  /usr/bin/python3 tests/terminal/pty_screen.py RAW [--interrupt-on REGEX] [--expect TEXT]... -- COMMAND...

Runs COMMAND on a pseudo-terminal (a session of its own, the terminal its
controlling one) and keeps every byte it writes there in RAW, as it comes.
--interrupt-on: once the text written so far matches REGEX, Ctrl-C is typed
(the terminal sends SIGINT to its foreground group, as a user's would).
When the command has ended (and everything it started has closed the
terminal), the bytes are fed to a VT100 emulator (pyte) and the screen, its
scrollback included, must hold:
  * every line the command printed as a log line ("[hh:mm:ss.mmm] [...") or
    as the runner's own ("afford: ..."), whole, in the order printed;
  * the progress board's last drawing, once: its first line as last drawn,
    and no other drawing of it;
  * each --expect TEXT in one of those lines (the scenario happened).
Exits 1 saying what is missing, else 0; prints the command's exit status.
"""
import argparse
import os
import pty
import re
import select
import signal
import struct
import sys
import termios
import fcntl
import time

import pyte

ROWS, COLUMNS = 50, 400

# Escape sequences: CSI (ESC [ ... final byte), and the two-byte others (ESC 7, ESC 8, ...).
ESCAPE = re.compile(r"\x1b\[[0-9;?]*[ -/]*[@-~]|\x1b[^\[]")
LOG_LINE = re.compile(r"^\[\d\d:\d\d:\d\d\.\d{3}\] \[|^afford: ")
BOARD_HEAD = re.compile(r": \d+ of \d+ done, \d+% of the steps")


def run(raw_path, command, interrupt_on):
    """The command on a pseudo-terminal; every byte kept in raw_path; its exit status."""
    pid, master = pty.fork()
    if pid == 0:
        try:
            os.execvp(command[0], command)
        finally:
            os._exit(127)
    fcntl.ioctl(master, termios.TIOCSWINSZ, struct.pack("HHHH", ROWS, COLUMNS, 0, 0))
    pattern = re.compile(interrupt_on) if interrupt_on else None
    text, interrupted = "", False
    deadline = time.monotonic() + 120  # a runner hung on the terminal: the test fails, it does not hang
    with open(raw_path, "wb") as raw:
        while True:
            ready, _, _ = select.select([master], [], [], 1.0)
            if time.monotonic() > deadline:
                os.kill(pid, signal.SIGKILL)
                sys.exit("the command did not end within 120 s")
            if not ready:
                continue
            try:
                chunk = os.read(master, 65536)
            except OSError:  # EIO: every writer of the terminal has closed it
                break
            if not chunk:
                break
            raw.write(chunk)
            raw.flush()
            if pattern and not interrupted:
                text += ESCAPE.sub("", chunk.decode("utf-8", "replace"))
                if pattern.search(text):
                    os.write(master, b"\x03")  # Ctrl-C, typed
                    interrupted = True
    _, status = os.waitpid(pid, 0)
    os.close(master)
    if pattern and not interrupted:
        sys.exit(f"the command ended before its output matched {interrupt_on!r}: nothing was interrupted")
    return os.waitstatus_to_exitcode(status)


def printed_lines(raw):
    """The lines written as log lines, in order (escape sequences and carriage returns taken out)."""
    text = ESCAPE.sub("", raw.decode("utf-8", "replace")).replace("\r", "")
    return [line.rstrip() for line in text.split("\n") if LOG_LINE.search(line)], \
        [line.rstrip() for line in text.split("\n") if BOARD_HEAD.search(line)]


def screen_rows(raw):
    """The emulated screen's rows at the end, scrollback first."""
    screen = pyte.HistoryScreen(COLUMNS, ROWS, history=100000)
    pyte.ByteStream(screen).feed(raw)
    rows = ["".join(row[x].data for x in range(COLUMNS)).rstrip() for row in screen.history.top]
    return rows + [row.rstrip() for row in screen.display]


def check(raw, expects):
    lines, boards = printed_lines(raw)
    rows = screen_rows(raw)
    problems = []
    for text in expects:
        if not any(text in line for line in lines):
            problems.append(f"no line printed holds {text!r} (the scenario did not happen)")
    at = 0
    for line in lines:
        if len(line) >= COLUMNS:
            problems.append(f"a line wider than the emulated terminal: {line!r}")
            continue
        try:
            at = rows.index(line, at) + 1
        except ValueError:
            where = "erased from the screen" if line not in rows else "on the screen out of order"
            problems.append(f"{where}: {line!r}")
    on_screen = [row for row in rows if BOARD_HEAD.search(row)]
    if not boards:
        problems.append("the progress board was never drawn")
    elif on_screen != [boards[-1]]:
        problems.append(f"the board's last drawing ({boards[-1]!r}) is not on the screen once, alone of its "
                        f"drawings: {on_screen}")
    return lines, rows, problems


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("raw")
    parser.add_argument("--interrupt-on")
    parser.add_argument("--expect", action="append", default=[])
    parser.add_argument("command", nargs="+")
    a = parser.parse_args()
    status = run(a.raw, a.command, a.interrupt_on)
    with open(a.raw, "rb") as f:
        raw = f.read()
    lines, rows, problems = check(raw, a.expect)
    print(f"exit status {status}; {len(lines)} line(s) printed, each checked on the final screen")
    if problems:
        print("the final screen (scrollback first):")
        print("\n".join("  | " + row for row in rows if row))
        print("\n".join(problems))
        sys.exit(1)


if __name__ == "__main__":
    main()
