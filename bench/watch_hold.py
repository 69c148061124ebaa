#!/usr/bin/env python3
"""afford watch's page held by clients that do not finish (docs/performance.md, "The page, held").

bench/run.sh watch-hold [--idle 1000] [--dribble 100] [--stalled 0] [--kept 0] [--unread 0]
                        [--seconds 30] [--port 8095] [--watcher-files N] [--afford PROGRAM] [--out DIR]

In a private network namespace, an `afford watch` (its bus empty) while this script holds, all at
once and for --seconds: --idle connections that send nothing, --dribble that send a request head one
byte a second and never end it, --stalled that send a request line and a field and stop, --kept that
are answered one request (keep-alive) and then stay idle, and --unread that ask for the event stream
and never read it. A connection the server closes is opened again at once, so each count is held
throughout. Meanwhile `GET /` from a new connection every half second: its time to the whole answer.
Then the watcher's memory (VmHWM) against its own before the hold, and a second `afford watch` on the
same port. Floor (exit 1 if missed): every `GET /` answered within 1 s, the watcher's peak at most
64 MB above its start, the second watcher refused, naming the address and port.

The watcher starts with the file limits of the shell that runs this (the held connections' are raised
here); --watcher-files N lowers its hard limit. --afford runs another build's program, to compare.
"""
import argparse
import multiprocessing
import os
import resource
import selectors
import socket
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
AFFORD = ROOT / "build" / "bin" / "afford"
FLOOR_LATENCY_S = 1.0
FLOOR_MB = 64


def private_netns():
    """Re-runs this script in a private network namespace (root), loopback up, multicast routed over it."""
    if not os.environ.get("AFFORD_TEST_NETNS"):
        os.execvp("unshare", ["unshare", "--net", "env", "AFFORD_TEST_NETNS=1", sys.executable, *sys.argv])
    subprocess.run(["ip", "link", "set", "lo", "up", "multicast", "on"], check=True)
    subprocess.run(["ip", "route", "add", "224.0.0.0/4", "dev", "lo"], check=True)


def tcp_counts():
    """This namespace's TCP counters: the listen queue's overflows and the segments sent again (a connection the
    kernel turned away, or a packet it dropped, waits about a second for its retry)."""
    found = {}
    for name in ("/proc/net/netstat", "/proc/net/snmp"):
        lines = Path(name).read_text().splitlines()
        for head, values in zip(lines[::2], lines[1::2]):
            found.update(zip(head.split()[1:], map(int, values.split()[1:])))
    return {"listen overflows": found["ListenOverflows"], "retransmitted": found["RetransSegs"]}


def kb(pid, field):
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith(field):
            return int(line.split()[1])
    return -1


class Holder:
    """The held connections: each kind's count kept open, a closed one opened again at once."""

    def __init__(self, port, counts, stop):
        self.port, self.counts, self.stop = port, counts, stop
        self.sel = selectors.DefaultSelector()
        self.reopened = {k: 0 for k in counts}

    def open(self, kind):
        s = socket.socket()
        if kind == "unread":
            s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        s.setblocking(False)
        s.connect_ex(("127.0.0.1", self.port))
        self.sel.register(s, selectors.EVENT_WRITE, [kind, 0])  # writable once connected

    def connected(self, key):
        s, (kind, _) = key.fileobj, key.data
        first = {"idle": b"", "dribble": b"GET / HTTP/1.1\r\nHost: x\r\nX-Dribble: ",
                 "stalled": b"GET /state HTTP/1.1\r\nHost: x\r\n", "kept": b"GET /state HTTP/1.1\r\nHost: x\r\n\r\n",
                 "unread": b"GET /events HTTP/1.1\r\nHost: x\r\n\r\n"}[kind]
        try:
            if first:
                s.send(first)
        except OSError:
            return self.closed(s, kind)
        # The stream is never read: not watched for reading (its buffer fills).
        self.sel.modify(s, 0 if kind == "unread" else selectors.EVENT_READ, [kind, 1])

    def closed(self, s, kind):
        self.sel.unregister(s)
        s.close()
        self.reopened[kind] += 1
        if not self.stop.is_set():
            self.open(kind)

    def readable(self, key):
        s, (kind, _) = key.fileobj, key.data
        try:
            data = s.recv(65536)
        except BlockingIOError:
            return
        except OSError:
            data = b""
        if not data:
            return self.closed(s, kind)
        # (a kept connection's answer is read and dropped: it then stays idle)

    def run(self, report):
        for kind, n in self.counts.items():
            for _ in range(n):
                self.open(kind)
        next_byte = time.monotonic() + 1
        while not self.stop.is_set():
            for key, events in self.sel.select(timeout=0.1):
                if key.data[1] == 0:
                    if events & selectors.EVENT_WRITE:
                        self.connected(key)
                elif events & selectors.EVENT_READ:
                    self.readable(key)
            if time.monotonic() >= next_byte:
                next_byte += 1
                for key in list(self.sel.get_map().values()):
                    if key.data == ["dribble", 1]:
                        try:
                            key.fileobj.send(b"a")
                        except OSError:
                            self.closed(key.fileobj, "dribble")
        held = sum(1 for k in self.sel.get_map().values() if k.data[1] == 1)
        report.send((held, self.reopened))
        for key in list(self.sel.get_map().values()):
            key.fileobj.close()


def hold(port, counts, stop, report):
    """The held connections, in a process of their own (the measured GET / does not wait for this one)."""
    Holder(port, counts, stop).run(report)


def get_page(port):
    """Seconds from connecting to the whole answer of GET /, and its status line."""
    t0 = time.monotonic()
    try:
        with socket.create_connection(("127.0.0.1", port), timeout=60) as s:
            s.sendall(b"GET / HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n")
            data = b""
            while chunk := s.recv(65536):
                data += chunk
    except OSError as e:
        return time.monotonic() - t0, f"no answer ({e})"
    return time.monotonic() - t0, data.split(b"\r\n", 1)[0].decode(errors="replace")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    for kind, n in (("idle", 1000), ("dribble", 100), ("stalled", 0), ("kept", 0), ("unread", 0)):
        ap.add_argument(f"--{kind}", type=int, default=n)
    ap.add_argument("--seconds", type=float, default=30)
    ap.add_argument("--port", type=int, default=8095)
    ap.add_argument("--watcher-files", type=int, default=0, help="the watcher's hard file limit (default: this shell's)")
    ap.add_argument("--afford", default=str(AFFORD), help="the afford program (another build's, to compare)")
    ap.add_argument("--out", default=str(ROOT / "out" / "bench-watch-hold"))
    a = ap.parse_args()
    private_netns()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    watcher_hard = min(hard, a.watcher_files) if a.watcher_files else hard
    resource.setrlimit(resource.RLIMIT_NOFILE, (hard, hard))
    counts = {k: getattr(a, k) for k in ("idle", "dribble", "stalled", "kept", "unread")}
    if sum(counts.values()) + 64 > hard:
        sys.exit(f"watch_hold.py: {sum(counts.values())} connections need more files than this limit allows ({hard})")

    log = open(out / "watch.log", "w")
    # (the watcher starts with this shell's file limit, not the one raised here for the held connections)
    watch = subprocess.Popen([a.afford, "watch", "--lcm-url", "udpm://239.255.76.67:7667?ttl=0",
                              "--port", str(a.port)], stdout=log, stderr=subprocess.STDOUT,
                             preexec_fn=lambda: resource.setrlimit(resource.RLIMIT_NOFILE, (soft, watcher_hard)))
    try:
        deadline = time.monotonic() + 30
        while "the page:" not in (out / "watch.log").read_text():
            if watch.poll() is not None or time.monotonic() > deadline:
                sys.exit("afford watch never served:\n" + (out / "watch.log").read_text())
            time.sleep(0.05)
        for _ in range(5):
            get_page(a.port)
        start_kb = kb(watch.pid, "VmHWM:")
        tcp = tcp_counts()
        files = next(l for l in Path(f"/proc/{watch.pid}/limits").read_text().splitlines() if "open files" in l)
        quiet = [get_page(a.port)[0] for _ in range(10)]

        stop, (report, reported) = multiprocessing.Event(), multiprocessing.Pipe()
        holder = multiprocessing.Process(target=hold, args=(a.port, counts, stop, reported), daemon=True)
        holder.start()
        t_end = time.monotonic() + a.seconds
        times, starts, statuses = [], [], set()
        while time.monotonic() < t_end:
            starts.append(a.seconds - (t_end - time.monotonic()))
            dt, status = get_page(a.port)
            times.append(dt)
            statuses.add(status)
            time.sleep(max(0.0, 0.5 - dt))
        peak_kb = kb(watch.pid, "VmHWM:")
        tcp = {k: v - tcp[k] for k, v in tcp_counts().items()}

        # A second watcher on the same port, while the first serves and is held.
        t0 = time.monotonic()
        second = subprocess.Popen([a.afford, "watch", "--lcm-url", "udpm://239.255.76.67:7667?ttl=0",
                                   "--port", str(a.port)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        try:
            said = second.communicate(timeout=10)[0]
        except subprocess.TimeoutExpired:  # it serves too
            second.terminate()
            said = second.communicate()[0] + "(still running after 10 s: stopped)"
        second_s = time.monotonic() - t0
        stop.set()
        held, reopened = report.recv()
        holder.join()
    finally:
        watch.terminate()
        watch.wait()

    said = said.strip()
    refused = second.returncode != 0 and f"127.0.0.1:{a.port}" in said
    grown_mb = (peak_kb - start_kb) / 1024
    lines = [
        f"held: {', '.join(f'{n} {k}' for k, n in counts.items() if n)} ({held} open at the end; opened again after the "
        f"server closed them: {', '.join(f'{k} {n}' for k, n in reopened.items() if counts[k])})",
        f"the watcher's file limit: soft {files.split()[3]}, hard {files.split()[4]} (this shell's soft limit: {soft})",
        f"GET / unheld: median {statistics.median(quiet) * 1000:.1f} ms, max {max(quiet) * 1000:.1f} ms",
        f"GET / held, {len(times)} over {a.seconds:.0f} s: median {statistics.median(times) * 1000:.1f} ms, "
        f"max {max(times) * 1000:.1f} ms ({starts[times.index(max(times))]:.1f} s into the hold), answers "
        f"{sorted(statuses)}; TCP meanwhile: {', '.join(f'{k} {v}' for k, v in tcp.items())}",
        f"watcher's peak: {start_kb / 1024:.1f} MB before the hold, {peak_kb / 1024:.1f} MB after (+{grown_mb:.1f} MB)",
        f"a second watcher on port {a.port}: exit {second.returncode} after {second_s:.2f} s: {said.splitlines()[-1] if said else ''}",
    ]
    ok = max(times) < FLOOR_LATENCY_S and statuses == {"HTTP/1.1 200 OK"} and grown_mb <= FLOOR_MB and refused
    lines.append(f"{'PASS' if ok else 'FAIL'} (floor: GET / within {FLOOR_LATENCY_S:.0f} s, +{FLOOR_MB} MB at most, "
                 f"a second watcher refused naming 127.0.0.1:{a.port})")
    (out / "results.txt").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
