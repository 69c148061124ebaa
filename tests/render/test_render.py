"""afford render on stored run logs, its files read by ffprobe.

  /usr/bin/python3 tests/render/test_render.py BUILD_DIR ARTEFACT_DIR

A video and a GIF of a run have one frame per step drawn (counted from the
log by the Python package: the steps of the messages the viewer draws), of
the size the command says; an existing file is refused and left as it was; a
failing encoder leaves nothing; a log cut mid-event still renders what it holds.
And the frames are a function of the log's messages, not of their order: the
same logs with their channels interleaved anew (shuffle-log: each channel in
its own order, the channels up to a window of steps apart, in two segments)
give the same frames, decoded pixel for pixel (ffmpeg's framemd5).
"""
import fcntl
import gzip
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
BUILD, OUT = Path(sys.argv[1]), Path(sys.argv[2])
AFFORD = BUILD / "bin" / "afford"
SHUFFLE = BUILD / "bin" / "shuffle-log"
sys.path.insert(0, str(BUILD / "python"))
import afford  # noqa: E402

# The channels whose messages move the viewer's step (processes/viewer/feed.hpp).
DRAWN = {"SCENE", "FOCUS", "PREDICTION", "DECISION", "EFFECT", "GOAL", "GOAL_RESULT"}


def render(log, out, *args, check=True):
    r = subprocess.run([str(AFFORD), "render", str(log), "--out", str(out), *args], capture_output=True, text=True)
    if check and r.returncode != 0:
        sys.exit(f"afford render {log} failed:\n{r.stdout}{r.stderr}")
    return r


def probe(video):
    r = subprocess.run(["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
                        "stream=nb_read_frames,width,height", "-of", "json", str(video)],
                       capture_output=True, text=True, check=True)
    s = json.loads(r.stdout)["streams"][0]
    return int(s["nb_read_frames"]), int(s["width"]), int(s["height"])


def expected_frames(log, every):
    """The steps drawn: each new highest step of the first run, one at least `every` after the last drawn."""
    run, top, steps = None, -1, []
    for m in afford.read_log(log):
        if m.channel == "RUN_CONFIG" and run is None:
            run = m["run_id"]
        if run is None or m.channel not in DRAWN or m["run_id"] != run:
            continue
        if m["step"] > top:
            top = m["step"]
            steps.append(top)
    drawn = []
    for s in steps:
        if not drawn or s - drawn[-1] >= every:
            drawn.append(s)
    return drawn


def frames_of(video):
    """The MD5 of each decoded frame."""
    r = subprocess.run(["ffmpeg", "-v", "error", "-i", str(video), "-f", "framemd5", "-"], capture_output=True,
                       text=True, check=True)
    return [line.split()[-1] for line in r.stdout.splitlines() if line and not line.startswith("#")]


def shuffled(log, out, window, seed=1):
    r = subprocess.run([str(SHUFFLE), str(log), str(out), "--window", str(window), "--seed", str(seed),
                        "--segments", "2"], capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"shuffle-log {log} failed:\n{r.stdout}{r.stderr}")
    return out, r.stdout.strip()


def same_frames_shuffled(log, every, window):
    """The log's video and its shuffled copy's: the same frames, at the same steps."""
    name = f"{Path(log).stem}-w{window}"
    copy, how = shuffled(log, OUT / f"{name}-shuffled", window)
    want, got = (render(l, OUT / f"{name}-{k}.mp4", "--every", str(every)) for k, l in (("log", log), ("shuffled", copy)))
    a, b = frames_of(OUT / f"{name}-log.mp4"), frames_of(OUT / f"{name}-shuffled.mp4")
    steps = [line for line in (want.stdout + got.stdout).splitlines() if line.startswith("wrote ")]
    differ = sum(x != y for x, y in zip(a, b)) + abs(len(a) - len(b))
    assert differ == 0, f"{name} ({how}): {differ} of {len(a)} frames differ from the log's ({steps})"
    assert steps[0].split(": ")[1] == steps[1].split(": ")[1], f"{name}: {steps}"
    assert len(a) == len(expected_frames(log, every)), f"{name}: {len(a)} frames"
    print(f"{name}: shuffled ({how}): the same {len(a)} frames")


def said(stdout):
    """(frames, width, height) as the command printed them."""
    line = next(l for l in stdout.splitlines() if l.startswith("wrote "))
    frames = int(line.split(": ")[1].split(" frames")[0])
    w, h = line.split(" frames of ")[1].split(",")[0].split("x")
    return frames, int(w), int(h)


def main():
    shutil.rmtree(OUT, ignore_errors=True)
    OUT.mkdir(parents=True)
    checked = 0
    for name, every in (("base-scenario3", 1), ("multi-step-top-down-budget", 3)):
        log = OUT / f"{name}.lcm"
        log.write_bytes(gzip.decompress((ROOT / "tests/data/explain" / f"{name}.lcm.gz").read_bytes()))
        want = expected_frames(log, every)
        assert len(want) >= 3, f"{name}: too few steps to test with ({want})"
        for ext in ("mp4", "gif"):
            video = OUT / f"{name}.{ext}"
            r = render(log, video, "--every", str(every))
            frames, w, h = said(r.stdout)
            got = probe(video)
            print(f"{video.name}: {got[0]} frames of {got[1]}x{got[2]} (the log's steps drawn: {len(want)})")
            assert frames == len(want), f"{video.name}: the command says {frames} frames, the log has {len(want)} steps to draw"
            assert got == (frames, w, h), f"{video.name}: ffprobe reads {got}, the command says {(frames, w, h)}"
            assert w >= 600 and h >= 400, f"{video.name}: {w}x{h} is smaller than the viewer's picture"
            checked += 1

    # An existing file is refused, its bytes untouched.
    video = OUT / "base-scenario3.mp4"
    before = video.read_bytes()
    r = render(OUT / "base-scenario3.lcm", video, check=False)
    assert r.returncode != 0 and "never overwrites" in r.stderr, r.stderr
    assert video.read_bytes() == before, "an existing video was changed"

    # An encoder that fails leaves neither the file nor its partial one.
    failed = OUT / "failed.mp4"
    r = render(OUT / "base-scenario3.lcm", failed, "--ffmpeg", "/bin/false", check=False)
    assert r.returncode != 0, "a failing ffmpeg went unnoticed"
    assert not failed.exists() and not Path(str(failed) + ".partial").exists(), "a failed render left a file"

    # What a render killed half-way left (its partial file, no writer holding it) is taken over by the next render
    # of the file; one a live render holds (its lock taken here, as a render at work holds it) is refused, naming it.
    left = OUT / "killed.mp4"
    Path(str(left) + ".partial").write_bytes(b"half a video")
    render(OUT / "base-scenario3.lcm", left)
    assert probe(left)[0] > 0 and not Path(str(left) + ".partial").exists(), "a killed render's partial file stayed"
    busy = OUT / "busy.mp4"
    with open(str(busy) + ".partial", "wb") as held:
        fcntl.flock(held, fcntl.LOCK_EX)
        r = render(OUT / "base-scenario3.lcm", busy, check=False)
    assert r.returncode != 0 and "busy.mp4.partial is being written by another afford render" in r.stderr, r.stderr
    assert not busy.exists(), "a render of a file being written wrote it"

    # A log cut in the middle of an event: what it holds is drawn.
    log = OUT / "multi-step-top-down-budget.lcm"
    cut = OUT / "cut.lcm"
    data = log.read_bytes()
    cut.write_bytes(data[: len(data) * 2 // 3 + 7])
    r = render(cut, OUT / "cut.mp4", "--every", "3")
    frames, _, _ = said(r.stdout)
    full, _, _ = said(render(log, OUT / "full-again.mp4", "--every", "3").stdout)
    assert 0 < frames < full, f"a cut log gave {frames} frames, the whole {full}"
    assert probe(OUT / "cut.mp4")[0] == frames
    # The same logs and a short intrinsic run's, their channels up to 20 and 1,000 steps apart.
    run = subprocess.run([str(AFFORD), "experiment", "base", "--system", "IMP", "--reps", "1", "--steps", "300",
                          "--transport", "memq", "--quiet", "--keep-logs", "all", "--run-prefix", "render",
                          "--out", str(OUT / "intrinsic"), "--log-root", str(OUT / "logs")], capture_output=True, text=True)
    assert run.returncode == 0, run.stdout + run.stderr
    intrinsic = OUT / "logs" / "render-base-IMP-s1"
    for log, every, window in ((intrinsic, 10, 20), (intrinsic, 10, 1000), (OUT / "multi-step-top-down-budget.lcm", 3, 50)):
        same_frames_shuffled(log, every, window)
    primitives = table_primitives()
    print(f"render: {checked} files checked; an existing file refused; a failed encoder left nothing; a cut log: "
          f"{frames} of {full} frames; shuffled logs give the same frames; {primitives}")


def table_primitives():
    """--primitive on a short table run: the action of a step that acted, simulated again up to it from the log
    (the command refuses unless its end is the scene the run published), drawn a frame every 1/fps s of physics
    with half a second before and a second after; a step that did not act, one the run never reached and a grid
    run's log are refused, each saying why, and nothing is written."""
    run = subprocess.run([str(AFFORD), "experiment", "table", "--system", "IMP", "--reps", "1", "--steps", "60",
                          "--set", "table.truth.trials=2", "--transport", "memq", "--quiet", "--run-prefix", "render",
                          "--out", str(OUT / "table"), "--log-root", str(OUT / "logs")], capture_output=True, text=True)
    assert run.returncode == 0, run.stdout + run.stderr
    log = OUT / "logs" / "render-table-IMP-s1"
    acted = [m["step"] for m in afford.read_log(log) if m.channel == "DECISION" and m["acted"]]
    idle = [m["step"] for m in afford.read_log(log) if m.channel == "DECISION" and not m["acted"]]
    assert len(acted) >= 2 and idle, f"the table run acted at {acted}, passed at {idle}"
    step = acted[-1]  # every action of the run before it simulated again
    video = OUT / "primitive.mp4"
    r = render(log, video, "--primitive", str(step), "--fps", "50")
    frames, w, h = said(r.stdout)
    assert probe(video) == (frames, w, h), f"ffprobe reads {probe(video)}, the command says {(frames, w, h)}"
    physics = int(r.stdout.split(" (")[1].split(" physics steps")[0])
    # table.timestep of the shipped table experiment, 4 ms: a frame every 1 / (50 x 0.004) = 5 physics steps
    assert frames == 25 + physics // 5 + 50, f"{frames} frames for {physics} physics steps"
    assert w == 2 * 2 * 320 and h == 2 * 240 + 36, f"{w}x{h}"
    assert f"at step {step}" in r.stdout and f"the run's {len(acted) - 1} earlier actions" in r.stdout, r.stdout
    for args, why in (((str(idle[-1]),), "the agent did not act"), (("100000",), "no DECISION of step 100000")):
        out = OUT / f"refused-{args[0]}.mp4"
        r = render(log, out, "--primitive", *args, check=False)
        assert r.returncode != 0 and why in r.stderr and "steps that acted near it: " in r.stderr, r.stderr
        assert not out.exists() and not Path(str(out) + ".partial").exists(), f"{out} written"
    r = render(OUT / "base-scenario3.lcm", OUT / "grid.mp4", "--primitive", "1", check=False)
    assert r.returncode != 0 and "world.kind: grid" in r.stderr, r.stderr
    return f"a table run's primitive at step {step}: {frames} frames of {w}x{h} ({physics} physics steps)"


if __name__ == "__main__":
    main()
