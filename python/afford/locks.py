"""A study's locks (afford.tune, python/afford/study.py): each a file lock (flock) that the kernel releases when
the process holding it dies, however it dies; nothing a killed worker leaves makes another wait. The list of
every lock afford takes, and what frees each: docs/operating.md#locks.

  claim(folder)        study.lock: asking for a trial and counting the trials, one worker at a time;
  JournalLock(path)    study.journal itself: Optuna's journal appends, one at a time (in place of Optuna's
                       symlink lock, which a holder killed while holding it leaves for good); journal(path)
                       reads it under a shared lock, so that no reader takes half a line being written;
  worker(folder)       workers/HOST.PID.START.K, held for as long as a tune() call runs: a trial whose
                       worker's file is free (or gone) has lost its worker, on this host or another.

And pyplot(): Matplotlib's own lock of its font cache, which is not the kernel's, broken when its holder is gone.
"""
from __future__ import annotations

import contextlib
import fcntl
import functools
import itertools
import json
import os
import socket
from pathlib import Path
from typing import Any, Iterator

WORKERS = "workers"  # the folder of a study's worker files


@contextlib.contextmanager
def claim(folder: Path) -> Iterator[None]:
    """The study's own lock (the kernel queues its waiters): asking for a trial and counting them."""
    with open(folder / "study.lock", "a") as f:
        fcntl.flock(f, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(f, fcntl.LOCK_UN)


def _ended(fd: int) -> bool:
    """The journal ends with a whole line (or is empty)."""
    size = os.fstat(fd).st_size
    return size == 0 or os.pread(fd, 1, size - 1) == b"\n"


def _repair(fd: int) -> None:
    """The journal's last line, when a holder was killed while writing it (the file does not end with a newline):
    cut off when it is not whole JSON, else ended with its newline. The taker holds the lock: nobody else writes
    meanwhile; and no reader has taken that line (a reader mends it first: Journal.read_logs)."""
    if _ended(fd):
        return
    size = os.fstat(fd).st_size
    start = 0
    for end in range(size, 0, -4096):  # the last newline, from the end back
        block = os.pread(fd, min(4096, end), max(0, end - 4096))
        if (i := block.rfind(b"\n")) >= 0:
            start = max(0, end - 4096) + i + 1
            break
    try:
        json.loads(os.pread(fd, size - start, start))
        os.pwrite(fd, b"\n", size)
    except ValueError:
        os.ftruncate(fd, start)
    os.fsync(fd)


class JournalLock:
    """The lock Optuna's JournalFileStorage takes around each append (its lock_obj: acquire, release), as a
    flock of the journal file itself. The taker first repairs a line a killed holder left half written."""

    def __init__(self, path: Path | str):
        self._path = str(path)
        self._fd: int | None = None

    def acquire(self) -> bool:
        fd = os.open(self._path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
            _repair(fd)
        except BaseException:
            os.close(fd)
            raise
        self._fd = fd
        return True

    def release(self) -> None:
        fd, self._fd = self._fd, None
        if fd is not None:
            os.close(fd)  # (the lock goes with the last descriptor of its open file)


@functools.cache
def _journal_class():
    from optuna.storages import JournalFileStorage

    class Journal(JournalFileStorage):
        """Optuna's journal file, each read under a shared flock: a line being appended (under JournalLock) is
        read whole, never in two pieces (Optuna's reader, reaching the end of the file in the middle of a line
        and going on as it grows, would take the two pieces for two bad lines and raise); a line a killed writer
        left unended is mended (JournalLock) before it is read."""

        def read_logs(self, log_number_from: int):
            fd = os.open(self._file_path, os.O_RDONLY | os.O_CLOEXEC)
            try:
                fcntl.flock(fd, fcntl.LOCK_SH)
                while not _ended(fd):  # (a line a killed writer left: mended under the writers' lock first)
                    fcntl.flock(fd, fcntl.LOCK_UN)
                    self._lock.acquire()
                    self._lock.release()
                    fcntl.flock(fd, fcntl.LOCK_SH)
                return super().read_logs(log_number_from)
            finally:
                os.close(fd)
    return Journal


def journal(path: Path):
    """Optuna's JournalFileStorage of the file `path`, with these locks (appends: JournalLock; reads: shared)."""
    return _journal_class()(str(path), lock_obj=JournalLock(path))


def start_time(pid: int) -> str | None:
    """The process's start time since boot (with its pid, a process of this host: pids are reused)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[19]
    except (OSError, IndexError):
        return None


_calls = itertools.count()  # this process's tune() calls: each is a worker of its own


@contextlib.contextmanager
def worker(folder: Path) -> Iterator[dict[str, Any]]:
    """This tune() call as a worker of the study in `folder`: who it is (host, pid, start time, and the file
    it holds locked while it runs), for the trials it claims."""
    host, pid = socket.gethostname(), os.getpid()
    started = start_time(pid)
    name = f"{WORKERS}/{host}.{pid}.{started}.{next(_calls)}"
    (folder / WORKERS).mkdir(exist_ok=True)
    fd = os.open(folder / name, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield {"host": host, "pid": pid, "started": started, "lock": name}
    finally:
        with contextlib.suppress(OSError):
            os.unlink(folder / name)
        os.close(fd)


def _free(path: Path) -> bool:
    """No process holds the worker file `path` (or it is gone: its worker ended, or was found dead)."""
    try:
        fd = os.open(path, os.O_RDWR | os.O_CLOEXEC)  # (writable: NFS takes a flock as a write lock)
    except FileNotFoundError:
        return True
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return False
    finally:
        os.close(fd)
    with contextlib.suppress(OSError):  # (its worker is dead: no one else will hold it again)
        os.unlink(path)
    return True


def gone(folder: Path, who: Any) -> bool:
    """The worker a trial names has ended or died: its file in workers/ is free, whatever host it ran on. A
    worker named without one (a study begun before worker files): gone when it ran on this host and its
    process is no longer running; another host's cannot be told."""
    if not isinstance(who, dict):
        return False
    lock = who.get("lock")
    if lock is not None:
        name = lock[len(WORKERS) + 1:] if isinstance(lock, str) and lock.startswith(WORKERS + "/") else ""
        if not name or "/" in name or name in (".", ".."):
            return False  # (not a name worker() gives: nothing to look at)
        return _free(folder / WORKERS / name)
    return who.get("host") == socket.gethostname() and start_time(int(who.get("pid", 0))) != who.get("started")


# Matplotlib holds its font cache's lock (a file made with O_EXCL) only while it writes the cache: milliseconds. One
# older than this was left by a process killed meanwhile, which every later Matplotlib would wait 5 s for and fail on.
MATPLOTLIB_LOCK_STALE_S = 60


def pyplot():
    """matplotlib.pyplot, drawing to files (Agg), after taking away a lock of Matplotlib's font cache that no live
    process holds (one older than MATPLOTLIB_LOCK_STALE_S): the lock is Matplotlib's own file, not a kernel lock,
    and a process killed while it wrote the cache left it for good."""
    import time

    import matplotlib
    matplotlib.use("Agg")
    for lock in Path(matplotlib.get_cachedir()).glob("*.matplotlib-lock"):
        with contextlib.suppress(FileNotFoundError):  # (another process took it away first)
            if time.time() - lock.stat().st_mtime > MATPLOTLIB_LOCK_STALE_S:
                lock.unlink()
    import matplotlib.pyplot as plt
    return plt
