#!/usr/bin/env python3
"""Every block of README.md and docs/*.md runs as written.

  tests/docs/run_blocks.py BUILD_DIR WORK_DIR DOC...

Each DOC (a markdown file of the checkout) runs in a folder of its own,
WORK_DIR/<name>, that holds the checkout's files (linked) with BUILD_DIR as
`build`, so its commands run as a reader at the checkout's top runs them:
`build/bin/afford`, `afford` (on PATH, as scripts/setup.sh links it),
`/usr/bin/python3` with the package, `scripts/procs.sh` with its group's
namespace. Its blocks run in order, so what one writes (out/base, a run's
log) the next reads. All of it inside a network namespace and a mount
namespace of its own: nothing leaves the machine, and the named namespaces a
block makes (`ip netns add`) are gone with it.

By language:
  sh        each block is one bash script (`set -e`: a failing line fails it)
  python    the blocks of one `##` section are one program, as a reader types
            them, run when the section's last Python block is reached
  yaml      written to a file (`file NAME`) or checked (`fragment`)
  text      shown output or a picture in words: not run
Any other language must say why it is not run (`skip`).

Directives (tests/docs/mdblocks.py), on the lines right above a fence:
  skip REASON          not run, for the reason given (a cluster, an hour of runs, an excerpt)
  small --opt V ...    every `afford experiment`, `afford tune`, `afford world truth` and `procs.sh run` of the block (every entry of
                       a plan file's block) takes these
                       options in place of its own (or beside them), and `afford.run`/`afford.tune` the same
                       as keywords (--extrinsic-reps 1 -> extrinsic_reps=1), where they take them: the size
                       a test affords, the rest as written
  small-for WORD --opt V ...  the same for the command lines that name WORD (!WORD: that do not name it)
  file NAME            the block is a file's text: written to NAME, or added to it if a block before wrote it
                       (not run; a Python block is part of its section's program too)
  fragment [EXP]       a yaml block that is part of an experiment file: `extends: EXP` (default base) and
                       the block must be a configuration `afford config` takes
  background K...      the block's K-th command lines (1 the first) start in the background, each as in a
                       terminal of its own, the others run in order around them; each is stopped with
                       SIGINT once the file's blocks have run, and must not have failed before (one that
                       ended by itself must have ended well)
  display              an X display for the block (Xvfb)
  before COMMAND       a shell command run first (not shown to a reader): what the block takes as given,
                       e.g. an experiment folder made by another page's commands
  set NAME=VALUE       NAME in the block stands for VALUE
`<run-id>` stands for the last run (not a test) whose log the blocks before made.
"""
import os
import re
import shlex
import signal
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(HERE))
from mdblocks import blocks  # noqa: E402

SHRINKS = re.compile(r"(afford experiment|afford tune|afford world truth|procs\.sh run)\b")
BLOCK_SECONDS = 300
# <run-id> in a shell block: the last run (not a test) whose log is in logs/ when the line runs.
LAST_RUN = r"""last_run() {
  local d; d=$(ls -td logs/*/manifest.json 2>/dev/null | xargs -r -n1 dirname | xargs -r -n1 basename |
               grep -v -E -- '-scenario|-e[0-9]+$' | head -n 1 || true)  # (pipefail: ls cut short by head)
  [[ -n $d ]] || { echo "<run-id>: no run's log in logs/ yet" >&2; return 1; }
  echo "$d"
}
"""


# Where no mount namespace can be made (a chroot, whose root is no mount point: `ip netns exec` cannot remount
# it either), a file runs in a network namespace of its own only, and these stand in for what needs one:
# a scripts/procs.sh group lives in that namespace (AFFORD_NETNS=none), and /opt is a folder of the file's.
FLAT = [("ip netns exec afford ", ""), ("ip netns delete afford", "true"), ("/opt/afford", "opt/afford")]


def sandboxed(doc: str, build: Path, work: Path) -> int:
    """Runs one file's blocks in network, mount and pid namespaces of their own (root): multicast routed over
    loopback, /run/netns (the namespaces `ip netns add` makes) and /opt (an install's prefix) empty and
    private; where mount namespaces cannot be made, in a network namespace only (FLAT)."""
    mounts = not os.environ.get("AFFORD_DOCS_FLAT") and subprocess.run(  # (AFFORD_DOCS_FLAT=1: as in a chroot)
        ["unshare", "--mount", "--propagation", "private", "true"], stderr=subprocess.DEVNULL).returncode == 0
    spaces = ["--net", "--mount", "--propagation", "private", "--pid", "--fork", "--mount-proc"] if mounts else ["--net"]
    env = dict(os.environ, AFFORD_DOCS_FLAT="" if mounts else "1")
    return subprocess.run(["unshare", *spaces, sys.executable, __file__, "--one", str(build), str(work), doc],
                          env=env).returncode


def enter_sandbox():
    subprocess.run(["ip", "link", "set", "lo", "up", "multicast", "on"], check=True)
    subprocess.run(["ip", "route", "add", "224.0.0.0/4", "dev", "lo"], check=True)
    if os.environ.get("AFFORD_DOCS_FLAT"):
        return
    for folder in ("/run/netns", "/opt"):
        Path(folder).mkdir(parents=True, exist_ok=True)
        subprocess.run(["mount", "-t", "tmpfs", "tmpfs", folder], check=True)


def end_left_behind(mark: str):
    """Ends every process that carries this file's mark in its environment (what a block left running: a
    group's processes, a job started with `&`); in a pid namespace of its own, its end does the same."""
    for pid_dir in Path("/proc").glob("[0-9]*"):
        try:
            if f"AFFORD_DOCS_RUN={mark}".encode() in (pid_dir / "environ").read_bytes().split(b"\0"):
                os.kill(int(pid_dir.name), signal.SIGKILL)
        except (OSError, ValueError):
            pass


def workdir(build: Path, work: Path) -> Path:
    work.mkdir(parents=True)
    for entry in ROOT.iterdir():
        if entry.name in ("docs", "examples", "tools"):  # copies: a block may write there (docs/ppo's figure)
            subprocess.run(["cp", "-r", str(entry), str(work / entry.name)], check=True)
        elif entry.name not in (".git", "build", "out", "logs", "studies", "run.mp4", "run.mcap"):
            (work / entry.name).symlink_to(entry)
    (work / "build").symlink_to(build)
    (work / "home").mkdir()
    return work


def shrink_line(line: str, options: list, entry: bool = False) -> str:
    """The command line with each (only, option, value) of `options` in place of its own, or added (where the
    line names `only`, if given); `entry`: a line of a plan file (`- NAME OPTIONS`)."""
    if not (SHRINKS.search(line) or entry and line.startswith("- ")) or "--resume" in line \
            or line.lstrip().startswith("#"):
        return line
    code, comment = (line.split(" # ", 1) + [""])[:2]
    # A command inside a quoted script (bash -c '... afford experiment ...'): the options go inside its quote.
    found = SHRINKS.search(code) or re.match(r"- ", code)
    end = code.rstrip()[-1:]
    quote = end if end in ("'", '"') and code[:found.start()].count(end) % 2 == 1 else ""
    code = code.rstrip()[:-1] if quote else code
    for only, opt, value in options:
        if only and bool(re.search(rf"(?<![\w-]){re.escape(only.lstrip('!'))}(?![\w-])", code)) == only.startswith("!"):
            continue
        pattern = re.compile(rf"(?<=\s){re.escape(opt)}(=|\s+)\S+")
        code = pattern.sub(f"{opt} {value}", code) if pattern.search(code) else f"{code.rstrip()} {opt} {value}"
    return code + quote + ("  # " + comment if comment else "")


def command_lines(text: str):
    """The block's lines with each continuation (a trailing backslash) joined to the next."""
    out, joined = [], ""
    for line in text.splitlines():
        if line.rstrip().endswith("\\"):
            joined += line.rstrip()[:-1].rstrip() + " "
        else:
            out.append(joined + line)
            joined = ""
    return out + ([joined] if joined else [])


def python_prelude(options: list) -> str:
    """Sets afford.run's and afford.tune's keywords that `small` gives, where they take them."""
    if not options:
        return ""
    kw = {opt.lstrip("-").replace("-", "_"): int(value) if value.isdigit() else value
          for only, opt, value in options if not only}
    return ("import functools as _ft, inspect as _insp, afford as _af\n"
            f"_small = {kw!r}\n"
            "def _sized(f):\n"
            "    takes = _insp.signature(f).parameters\n"
            "    @_ft.wraps(f)\n"
            "    def g(*a, **k):\n"
            "        k.update({n: v for n, v in _small.items() if n in takes})\n"
            "        return f(*a, **k)\n"
            "    return g\n"
            "_af.run, _af.tune = _sized(_af.run), _sized(_af.tune)\n")


def directives_of(b) -> dict:
    """The block's directives: `small` as a list of (only, option, value), the others by name."""
    d = {"small": []}
    for name, arg in b.directives:
        if name in ("small", "small-for"):
            words = shlex.split(arg)
            only = words.pop(0) if name == "small-for" else None
            d["small"] += [(only, o, v) for o, v in zip(words[::2], words[1::2])]
        elif name != "set":
            d[name] = arg
    return d


class Doc:
    """One markdown file's blocks, run in order in its own folder."""

    def __init__(self, doc: Path, build: Path, work: Path):
        self.doc, self.name = doc, doc.relative_to(ROOT).as_posix()
        self.work = workdir(build, work / doc.stem)
        self.env = dict(os.environ, HOME=str(self.work / "home"), AFFORD_BIN=str(build / "bin"),
                        PATH=f"{build / 'bin'}:{os.environ['PATH']}",
                        PYTHONPATH=":".join(p for p in (str(build / "python"), os.environ.get("PYTHONPATH")) if p))
        self.env.pop("AFFORD_LOGS", None)
        self.env["TMPDIR"] = str(self.work / "tmp")  # (afford.run's folders without `out`: the file's, not /tmp's)
        (self.work / "tmp").mkdir()
        self.mark = f"{os.getpid()}-{time.time_ns()}"
        self.env["AFFORD_DOCS_RUN"] = self.mark
        self.flat, self.flattened = bool(os.environ.get("AFFORD_DOCS_FLAT")), set()
        if self.flat:
            self.env["AFFORD_NETNS"] = "none"
        self.background, self.failures, self.ran, self.skipped = [], [], 0, []
        self.xvfb = None
        self.written = set()
        self.times = []  # (seconds, where) of each block
        self.logs = self.work / ".blocks"
        self.logs.mkdir()

    def where(self, b) -> str:
        return f"{self.name}:{b.start - 1}"

    def fail(self, b, what: str, log: Path | None = None):
        tail = "\n".join(log.read_text(errors="replace").splitlines()[-30:]) if log and log.exists() else ""
        self.failures.append(f"{self.where(b)} ({b.section}): {what}" + (f"\n{tail}" if tail else ""))

    def substitute(self, b, text: str) -> str:
        for name, arg in b.directives:
            if name == "set":
                key, _, value = arg.partition("=")
                text = text.replace(key, value)
        if self.flat and b.lang in ("sh", "bash"):
            for written, here in FLAT:
                if written in text:
                    text = text.replace(written, here)
                    self.flattened.add(written.strip())
        return text.replace("<run-id>", "$(last_run)") if b.lang in ("sh", "bash") else text

    def last_run(self, b) -> str | None:
        """The run (not a test) whose log the blocks before made last."""
        runs = sorted((p for p in (self.work / "logs").glob("*") if (p / "manifest.json").exists()
                       and not re.search(r"-scenario|-e\d+$", p.name)), key=lambda p: p.stat().st_mtime)
        if not runs:
            self.fail(b, "it names logs/<run-id>, and no block before it made a run's log")
        return runs[-1].name if runs else None
        return text

    def display(self):
        if self.xvfb is None:
            r, w = os.pipe()
            self.xvfb = subprocess.Popen(["Xvfb", "-displayfd", str(w), "-screen", "0", "1280x1024x24", "-nolisten",
                                          "tcp"], pass_fds=(w,), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            os.close(w)
            with os.fdopen(r) as f:
                self.env_display = ":" + f.readline().strip()
        return {"DISPLAY": self.env_display}

    def run_sh(self, b, text: str, d: dict):
        lines = [shrink_line(line, d["small"]) for line in command_lines(text)]
        env = dict(self.env, **(self.display() if "display" in d else {}))
        commands = [k for k, line in enumerate(lines) if line.strip() and not line.lstrip().startswith("#")]
        behind = {commands[int(i) - 1] for i in d.get("background", "").split()}
        script = []
        for k, line in enumerate(lines + [""]):
            if k not in behind and k < len(lines):
                script.append(line)
                continue
            if any(x.strip() for x in script) and not self.run_script(b, "\n".join(script), env, f"{b.start}-{k}"):
                return
            script = []
            if k in behind:
                log = self.logs / f"{b.start}-{k}.log"
                p = subprocess.Popen(["bash", "-c", LAST_RUN + line], cwd=self.work, env=env, stdout=log.open("w"),
                                     stderr=subprocess.STDOUT, start_new_session=True,  # (Ctrl-C as in a terminal)
                                     preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
                self.background.append((b, line, p, log))

    def run_script(self, b, script: str, env: dict, name: str) -> bool:
        log = self.logs / f"{name}.log"
        with log.open("w") as out:
            p = subprocess.Popen(["bash", "-e", "-o", "pipefail", "-c", LAST_RUN + script], cwd=self.work, env=env,
                                 stdout=out, stderr=subprocess.STDOUT, start_new_session=True)
            try:  # (what it starts in the background, as a terminal's jobs, runs on: the file's end stops it)
                code = p.wait(timeout=BLOCK_SECONDS)
            except subprocess.TimeoutExpired:
                code = None
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()
        if code is None:
            self.fail(b, f"still running after {BLOCK_SECONDS} s", log)
        elif code:
            self.fail(b, f"exit code {code}", log)
        return code == 0

    def run_python(self, b, source: str, small: list):
        path = self.logs / f"{b.start}.py"
        if "<run-id>" in source:
            run = self.last_run(b)
            if run is None:
                return
            source = source.replace("<run-id>", run)
        path.write_text(python_prelude(small) + source)
        log = self.logs / f"{b.start}.log"
        with log.open("w") as out:
            try:
                r = subprocess.run(["/usr/bin/python3", str(path)], cwd=self.work, env=self.env, stdout=out,
                                   stderr=subprocess.STDOUT, timeout=BLOCK_SECONDS)
            except subprocess.TimeoutExpired:
                return self.fail(b, f"still running after {BLOCK_SECONDS} s", log)
        if r.returncode:
            self.fail(b, f"the section's Python exits with code {r.returncode}", log)

    def run(self):
        all_blocks = list(blocks(self.doc))
        last_python = {b.section: b.start for b in all_blocks if b.lang == "python"}
        python, python_small = {}, {}
        for b in all_blocks:
            d = directives_of(b)
            began = time.time()
            self.run_block(b, d, python, python_small, last_python)
            self.times.append((time.time() - began, self.where(b)))
        self.stop_background()
        return self

    def run_block(self, b, d: dict, python: dict, python_small: dict, last_python: dict):
        if "skip" in d:
            if not d["skip"]:
                self.fail(b, "`skip` says no reason")
            self.skipped.append(f"{self.where(b)}: {d['skip']}")
            return
        if b.lang == "text":
            return
        text = self.substitute(b, b.text)
        if not text:
            return
        if "before" in d and not self.run_script(b, d["before"], self.env, f"{b.start}-before"):
            return
        self.ran += 1
        if "file" in d:  # (a second block of the same file adds to it, as a reader adds a class to mine.py)
            path = self.work / d["file"]
            path.parent.mkdir(parents=True, exist_ok=True)
            with path.open("a" if path in self.written else "w") as f:
                f.write("\n".join(shrink_line(line, d["small"], entry=True) for line in text.splitlines()) + "\n")
            self.written.add(path)
        if "file" in d and b.lang != "python":
            return
        if b.lang in ("sh", "bash"):
            self.run_sh(b, text, d)
        elif b.lang == "python":
            lines = python.setdefault(b.section, [])
            lines += [""] * (b.start - 1 - len(lines)) + text.splitlines()
            python_small.setdefault(b.section, []).extend(d["small"])
            if b.start == last_python[b.section]:
                self.run_python(b, "\n".join(lines) + "\n", python_small[b.section])
        elif b.lang == "yaml" and "fragment" in d:
            self.check_fragment(b, text, d["fragment"] or "base")
        else:
            self.ran -= 1
            self.fail(b, f"a block of language {b.lang or '(none)'!r} is neither run nor marked: give it a "
                         "language (text for output), or a directive (file, fragment, skip REASON)")

    def check_fragment(self, b, text: str, base: str):
        path = self.logs / f"{b.start}.yaml"
        path.write_text(f"extends: {base}\n{text}\n" if not text.lstrip().startswith("extends:") else text + "\n")
        log = self.logs / f"{b.start}.log"
        with log.open("w") as out:
            r = subprocess.run(["build/bin/afford", "config", str(path)], cwd=self.work, env=self.env, stdout=out,
                               stderr=subprocess.STDOUT, timeout=60)
        if r.returncode:
            self.fail(b, "the fragment is not a configuration afford takes", log)

    def stop_background(self):
        for b, line, p, log in self.background:
            if p.poll() is not None:
                if p.returncode:
                    self.fail(b, f"`{line}` failed (exit code {p.returncode}) before the file's blocks had run", log)
                continue
            os.killpg(p.pid, signal.SIGINT)
        for b, line, p, log in self.background:
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                self.fail(b, f"`{line}` did not stop within 30 s of SIGINT", log)
        if self.xvfb:
            self.xvfb.terminate()
            self.xvfb.wait()
        end_left_behind(self.mark)


def main():
    one = sys.argv[1:2] == ["--one"]
    args = sys.argv[2:] if one else sys.argv[1:]
    if len(args) < 3:
        sys.exit(__doc__)
    build, work = Path(args[0]).resolve(), Path(args[1]).resolve()
    if one:
        enter_sandbox()
        started = time.time()
        d = Doc((ROOT / args[2]).resolve(), build, work).run()
        print(f"{d.name}: {d.ran} blocks run, {len(d.skipped)} not run, {len(d.failures)} failed "
              f"({time.time() - started:.0f} s)", flush=True)
        if d.flattened:
            print("  no mount namespace here: run in the file's network namespace in place of "
                  + ", ".join(f"`{w}`" for w in sorted(d.flattened)))
        for seconds, where in sorted(d.times, reverse=True)[:3]:
            print(f"  slowest: {where} {seconds:.1f} s")
        for s in d.skipped:
            print(f"  not run: {s}")
        for f in d.failures:
            print(f"  FAILED {f}")
        sys.exit(1 if d.failures else 0)
    if work.exists():
        subprocess.run(["rm", "-rf", str(work)], check=True)
    work.mkdir(parents=True)
    codes = [sandboxed(doc, build, work) for doc in args[2:]]
    sys.exit(1 if any(codes) else 0)


if __name__ == "__main__":
    main()
