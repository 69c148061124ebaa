"""afford watch's page in headless Chromium (Selenium and chromedriver, from Debian).

  browser.py live URL OUT        start Chromium (then touch OUT/page-ready), open the page as soon as it is
                                 served (afford experiment --watch serves it), follow a GOALS run and its
                                 tests until OUT/run/summary.json exists, then check the page against the
                                 run's log (OUT/logs): its step advanced, each scene it showed is the log's
                                 scene of that step, it was never more than a second behind the run, its
                                 curves grew; in the goals phase its trace drew the modules' competence and
                                 its goals table said what an exploration is and its goal panel showed the
                                 agent's own goal image; at the end (the page's last
                                 state) every run heard is done, the last test's goal image is shown, and
                                 shown again after another run without one; at 1280 px the curves have
                                 their axes' ticks and the legend beside them; screenshots
                                 OUT/watch-live.png (goals phase), OUT/watch-end.png (the end, 1280 px)
  browser.py playback URL OUT [IDLE_URL]  the controls of a log's playback: step, seek, play, pause, speed;
                                 then IDLE_URL, a page with no run: it says so, and shows no step
                                 (OUT/watch-idle.png)
  browser.py table URL OUT LOG    a table run's log played: its scene as the run published it, its actions named
                                 (OUT/watch-table.png)
  browser.py hold URL FILE READY once the page follows, touch READY; keep it open until FILE exists
                                 (bench/watch.sh); print the states it took
  browser.py stream URL FILE READY  the same without a browser: a client reading the page's event stream
  browser.py token URL           a server bound off loopback: without the token, or with another, every
                                 request is refused (401); with it, served
"""
import base64
import bisect
import io
import json
import os
import shutil
import signal
import tempfile
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

import matplotlib.image
import numpy as np

HERE = Path(__file__).resolve()


class Browser:
    """Headless Chromium driven by chromedriver, its profile in a folder of its own; on leaving, every process
    started with that profile is ended (quitting the driver leaves some of Chromium's running)."""

    def __enter__(self):
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
        self.profile = tempfile.mkdtemp(prefix="afford-chromium-")
        o = webdriver.ChromeOptions()
        o.binary_location = "/usr/bin/chromium"
        # As root in a closed network: no sandbox, nothing fetched in the background.
        for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update", "--disable-sync",
                  "--disable-dev-shm-usage", "--window-size=1300,1000", f"--user-data-dir={self.profile}",
                  *os.environ.get("AFFORD_CHROMIUM_ARGS", "").split()):
            o.add_argument(a)
        self.driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=o)
        return self.driver

    def __exit__(self, *exc):
        try:
            self.driver.quit()
        finally:
            for pid in filter(str.isdigit, os.listdir("/proc")):
                try:
                    if self.profile.encode() in Path(f"/proc/{pid}/cmdline").read_bytes():
                        os.kill(int(pid), signal.SIGKILL)
                except (OSError, ProcessLookupError):
                    pass
            shutil.rmtree(self.profile, ignore_errors=True)


def wait(what, cond, seconds=30.0):
    deadline = time.time() + seconds
    while time.time() < deadline:
        v = cond()
        if v:
            return v
        time.sleep(0.05)
    sys.exit(f"timed out waiting for {what}")


def shown(d):
    """What the page shows now: its step, its scene's step and pixels, its curves' points."""
    return d.execute_script("""
      const img = document.getElementById('scene');
      return {step: Number(document.body.dataset.step ?? -1), scene_step: img.dataset.step,
              scene: img.getAttribute('src'), points: window.afford.curvePoints,
              run: window.afford.state ? window.afford.state.run.id : '', states: window.afford.states};""")


def pixels(data_url):
    png = base64.b64decode(data_url.split(",", 1)[1])
    img = matplotlib.image.imread(io.BytesIO(png), format="png")
    return np.rint(img[:, :, :3] * 255).astype(np.uint8)


def scenes_of(log):
    """The run's scenes by step (the last one of a step), and (utime, step) of every message of the run."""
    import afford
    scenes, times = {}, []
    for m in afford.read_log(log):
        if "step" not in m.fields or m.channel in ("RUN_CONFIG", "RUN_CONTROL"):
            continue
        times.append((m.utime, m["step"]))
        if m.channel == "SCENE" and m["cause"] != 4:  # not an extrinsic test's goal
            scenes[m["step"]] = m["image"]
    return scenes, times


def goals_phase(d):
    """In the goals phase: the trace's lines and title, the goals table's text."""
    return d.execute_script("""
      const s = window.afford.state;
      return {phase: s ? s.run.phase : '', lines: Number(document.getElementById('trace').dataset.lines),
              title: document.getElementById('trace-title').textContent,
              goals: document.getElementById('goals').innerText,
              goal: s && s.sub_goal && s.goal_text !== '' && !s.goal
                    && document.getElementById('goal').getAttribute('src') === s.sub_goal.png
                    && document.getElementById('goal').naturalWidth > 0,
              oneRow: document.getElementById('bars').closest('.panel').getBoundingClientRect().top
                      === document.getElementById('scene').closest('.panel').getBoundingClientRect().top};""")


def the_end(d, out):
    """The page's last state, the experiment over: runs heard, the goal image, the curves' axes at 1280 px."""
    # The experiment sends the pages following it what they have not seen, then closes: its end is in.
    wait("the experiment's page closed", lambda: d.execute_script(
        "return document.getElementById('lost').style.display === 'inline'"), 30)
    runs = d.execute_script("""return [...document.getElementById('runs').rows].slice(1).map(
        (r) => [r.cells[0].textContent, r.cells[3].textContent, r.cells[5].textContent]);""")
    assert len(runs) >= 3 and all(state == "done" for _, _, state in runs), f"runs heard at the end: {runs}"
    assert sum(phase == "extrinsic" for _, phase, _ in runs) >= 2, f"the tests are not among the runs heard: {runs}"
    goal = lambda: d.execute_script("""const g = document.getElementById('goal'), s = window.afford.state;
        return {has: !!s.goal, same: !!s.goal && g.getAttribute('src') === s.goal.png, width: g.naturalWidth,
                test: s.run.phase};""")
    g = goal()
    assert g["test"] == "extrinsic" and g["has"], f"the page's last state is not a test with its goal: {g}"
    wait("the goal image drawn", lambda: goal()["same"] and goal()["width"] > 0, 5)
    # Another run without a goal image shown, then this one again (the next test of the same scenario).
    d.execute_script("const s = window.afford.state; show(Object.assign({}, s, {goal: null})); show(s);")
    wait("the same goal image shown again", lambda: goal()["same"] and goal()["width"] > 0, 5)
    d.set_window_size(1280, 1000)
    axes = lambda: d.execute_script("""
      const canvases = [...document.querySelectorAll('#curves canvas')], legend = document.getElementById('curve-legend');
      const last = canvases[canvases.length - 1].getBoundingClientRect(), l = legend.getBoundingClientRect();
      return {width: window.innerWidth, canvas_right: last.right, canvas_top: last.top, canvas_bottom: last.bottom,
              legend_left: l.left, legend_top: l.top, legend_right: l.right,
              x: [...document.querySelectorAll('.xaxis')].map((a) => [...a.children].map((t) => t.textContent)),
              y: [...document.querySelectorAll('.yaxis')].map((a) => [...a.children].map((t) => t.textContent))};""")
    wait("the window at 1280 px", lambda: axes()["width"] <= 1280)
    # The goals run's curves (a test has none) drawn again at this width (the x ticks follow the canvas).
    d.execute_script("showCurves(window.goalsCurves);")
    a = axes()
    assert a["legend_left"] >= a["canvas_right"] and a["legend_top"] < a["canvas_bottom"] and \
        a["legend_right"] <= a["width"], f"at 1280 px the legend is not beside the curves: {a}"
    assert all(y == ["1", "0.5", "0"] for y in a["y"]) and len(a["y"]) == 4, f"the y axes' ticks: {a['y']}"
    for x in a["x"]:
        steps = [int(t) for t in x]
        assert len(steps) >= 2 and steps == sorted(steps), f"the x axis' ticks: {a['x']}"
    d.save_screenshot(str(Path(out) / "watch-end.png"))
    return runs, a["x"][0]


def behind(drawn, run, times):
    """The most the page was behind the run: a step of the run stays on the page until the page draws the next
    state; by then the run may have gone past it (a message of a later step in the log) a while before."""
    assert sum(r == run for _, _, r in drawn) >= 5, f"the page drew few states of run {run}: {drawn[:10]}"
    earliest = {}
    for u, st in times:
        earliest[st] = min(u, earliest.get(st, u))
    steps = sorted(earliest)
    past = [0] * len(steps)  # past[i]: the first moment of a message of a step after steps[i]
    for i in range(len(steps) - 2, -1, -1):
        past[i] = min(earliest[steps[i + 1]], past[i + 1]) if i + 2 < len(steps) else earliest[steps[i + 1]]
    worst = 0.0
    for (t, step, r), (t_next, _, _) in zip(drawn, drawn[1:]):
        i = bisect.bisect_right(steps, step) - 1  # the last step of the log at or before the one drawn
        if r == run and 0 <= i < len(steps) - 1:
            worst = max(worst, t_next / 1e3 - past[i] / 1e6)
    return worst


def live(url, out):
    out = Path(out)
    samples, shot, goals_seen = [], False, []
    with Browser() as d:
        (out / "page-ready").touch()  # Chromium is up: the experiment may start, and serve the page
        def opened():  # (Chromium shows its own error page while nothing is served: no window.afford)
            d.get(url)
            until = time.time() + 5
            while time.time() < until and d.execute_script("return !!window.afford"):
                if d.execute_script("return window.afford.states") > 0:
                    return True
                time.sleep(0.05)
            return False
        wait("the page served", opened, 60)
        # Each state as the page drew it, stamped by the page itself: how far behind it was is the page's own
        # record, not the moment this script got round to asking (a loaded machine delays the driver's calls).
        d.execute_script("""window.drawn = []; new MutationObserver(() => window.drawn.push([Date.now(),
          Number(document.body.dataset.step), window.afford.state ? window.afford.state.run.id : ''])).observe(
          document.body, {attributes: true, attributeFilter: ['data-step']});""")
        wait("the page to show a run", lambda: shown(d)["step"] > 0, 60)
        while not (out / "run" / "summary.json").exists():
            s = shown(d)
            samples.append(s)
            g = goals_phase(d)
            if g["phase"] == "goals":
                d.execute_script("const s = window.afford.state; if (s.curves && s.curves.steps.length > 1) "
                                 "window.goalsCurves = s.curves;")
                goals_seen.append(g)
                if not shot and s["step"] >= 1000:
                    # The agent's own goal (no goal scene in this phase) is drawn in the goal panel.
                    wait("the goals phase's goal image drawn", lambda: goals_phase(d)["goal"], 5)
                    d.save_screenshot(str(out / "watch-live.png"))
                    assert goals_phase(d)["oneRow"], "the goal panel pushed the affordance panel to another row"
                    shot = True
            time.sleep(0.1)
        states = d.execute_script("return window.drawn")
        runs, x_ticks = the_end(d, out)
    run = samples[0]["run"]
    samples = [s for s in samples if s["run"] == run and s["scene"]]
    assert len({s["step"] for s in samples}) >= 5, f"the page's step hardly moved: {[s['step'] for s in samples]}"
    assert shot, "no screenshot: the page never showed step 1000 of the goals phase"
    drawn = [g for g in goals_seen if g["lines"] > 0]
    assert drawn and "competence per module" in drawn[-1]["title"], f"the goals phase's trace: {goals_seen[-1:]}"
    assert "explorations (random actions: no goal image to reach)" in drawn[-1]["goals"] and \
        " of " not in drawn[-1]["goals"].split("explore")[1].split("\n")[0], f"the goals table: {drawn[-1]['goals']}"
    scenes, times = scenes_of(out / "logs" / run)
    checked = 0
    for s in samples:
        step = int(s["scene_step"])
        want = scenes.get(step)
        assert want is not None, f"the page shows a scene of step {step}, which the log does not have"
        got = pixels(s["scene"])
        assert got.shape == want.shape and (got == want).all(), f"the page's scene of step {step} is not the log's"
        checked += 1
    worst = behind(states, run, times)
    assert worst <= 1.0, f"the page was {worst:.2f} s behind the run"
    points = [s["points"] for s in samples]
    assert points[-1] > points[0] >= 0 and points[-1] >= 5, f"the curves did not grow: {points[0]} -> {points[-1]}"
    print(f"live: {len(samples)} looks at run {run}, steps {samples[0]['step']} to {samples[-1]['step']}; "
          f"{checked} scenes equal the log's; at most {max(worst, 0):.2f} s behind; curves {points[0]} -> {points[-1]} "
          f"points; competence drawn over {drawn[-1]['lines']} goals; at the end {len(runs)} runs heard, all done; "
          f"the goal image shown again; at 1280 px the legend beside the curves, steps ticked {x_ticks}")


def idle(d, url, out):
    d.get(url)
    wait("the page's first state", lambda: d.execute_script("return window.afford.states") > 0)
    status = d.execute_script("return document.getElementById('status').innerText")
    d.save_screenshot(str(Path(out) / "watch-idle.png"))
    assert "-1" not in status and "no run heard yet" in status, f"the idle page says: {status!r}"
    print(f"idle: {status.strip()!r}")


def playback(url, out, idle_url=None):
    with Browser() as d:
        d.get(url)
        wait("the first step", lambda: shown(d)["scene"] and shown(d)["step"] >= 0)
        s0 = shown(d)["step"]
        d.find_element("id", "step-once").click()
        wait("a step", lambda: shown(d)["step"] > s0)
        s1 = shown(d)["step"]
        assert s1 == s0 + 1, f"step moved from {s0} to {s1}"
        d.execute_script("const s = document.getElementById('seek'); s.value = 1500;"
                         "s.dispatchEvent(new Event('change'));")
        wait("the seek", lambda: shown(d)["step"] == 1500)
        back = int(shown(d)["scene_step"])
        d.execute_script("const s = document.getElementById('seek'); s.value = 200;"
                         "s.dispatchEvent(new Event('change'));")
        wait("the seek back", lambda: shown(d)["step"] == 200)
        d.execute_script("const s = document.getElementById('speed'); s.value = '500';"
                         "s.dispatchEvent(new Event('change'));")
        wait("the speed", lambda: d.execute_script("return window.afford.state.playback.speed") == 500)
        d.find_element("id", "play").click()
        wait("playing", lambda: shown(d)["step"] > 400, 20)
        d.find_element("id", "pause").click()
        wait("paused", lambda: not d.execute_script("return window.afford.state.playback.playing"))
        time.sleep(0.3)
        held = shown(d)["step"]
        time.sleep(0.5)
        assert shown(d)["step"] == held, "the playback went on after pause"
        d.save_screenshot(str(Path(out) / "watch-playback.png"))
        print(f"playback: step {s0} -> {s1}; seek 1500 (scene of step {back}), back to 200; played to {held} at "
              f"500 steps/s; paused")
        if idle_url:
            idle(d, idle_url, out)


def table(url, out, log):
    """A table run's log played (world.kind: table): the scene the page shows at a step is the camera's image the
    run published, 240 x 320, pixel for pixel; the affordance bars and the curves are named by the table's
    actions. Screenshot OUT/watch-table.png."""
    scenes, _ = scenes_of(log)
    with Browser() as d:
        d.get(url)
        wait("the first step", lambda: shown(d)["scene"] and shown(d)["step"] >= 0)
        d.execute_script("const s = document.getElementById('seek'); s.value = 30;"
                         "s.dispatchEvent(new Event('change'));")
        wait("the seek", lambda: shown(d)["step"] == 30)
        at = int(shown(d)["scene_step"])
        seen = pixels(shown(d)["scene"])
        assert seen.shape == (240, 320, 3), f"the page's scene is {seen.shape}"
        assert np.array_equal(seen, scenes[at]), f"the page's scene of step {at} is not the run's"
        text = d.find_element("tag name", "body").text
        for name in ("push", "carry", "topple", "roll"):
            assert name in text, f"'{name}' is not on the page:\n{text[:600]}"
        assert "turn green" not in text, "the page names the paper's actions for a table run"
        d.save_screenshot(str(Path(out) / "watch-table.png"))
        print(f"table: the scene of step {at}, 320 x 240, as the run published it; its actions named")


def hold(url, until, ready):
    with Browser() as d:
        d.get(url)
        wait("the page's first state", lambda: d.execute_script("return window.afford.states") > 0)
        Path(ready).touch()
        while not Path(until).exists():
            time.sleep(0.2)
        print(f"the page took {d.execute_script('return window.afford.states')} states")


def stream(url, until, ready):
    """A page elsewhere, as the run's machine sees it: a client reading the event stream (no browser here)."""
    states = 0
    with urllib.request.urlopen(url.rstrip("/") + "/events", timeout=30) as r:
        Path(ready).touch()
        while not Path(until).exists():
            line = r.readline()
            if not line:
                break
            states += line.startswith(b"event: state")
    print(f"the stream took {states} states")


def token(url):
    base = url.split("?")[0]
    good = url.split("token=")[1]
    def status(u):
        try:
            with urllib.request.urlopen(u, timeout=10) as r:
                return r.status
        except urllib.error.HTTPError as e:
            return e.code
    for path in ("", "state", "events?x=1"):
        assert status(base + path) == 401, f"/{path} without the token was not refused"
        assert status(base + path + ("&" if "?" in path else "?") + "token=" + "0" * len(good)) == 401
    req = urllib.request.Request(base + "state", headers={"Authorization": "Bearer " + good})
    with urllib.request.urlopen(req, timeout=10) as r:
        assert r.status == 200 and "step" in json.loads(r.read())
    assert status(base + "state?token=" + good) == 200
    print("token: every request without it or with another refused (401); with it served")


if __name__ == "__main__":
    mode = sys.argv[1]
    if mode == "live":
        live(sys.argv[2], sys.argv[3])
    elif mode == "playback":
        playback(sys.argv[2], sys.argv[3], sys.argv[4] if len(sys.argv) > 4 else None)
    elif mode == "stream":
        stream(sys.argv[2], sys.argv[3], sys.argv[4])
    elif mode == "table":
        table(sys.argv[2], sys.argv[3], sys.argv[4])
    elif mode == "hold":
        hold(sys.argv[2], sys.argv[3], sys.argv[4])
    else:
        token(sys.argv[2])
