"""The messages of an exported MCAP file, as tools/mcapcheck/check.mjs printed them (JSON lines),
against the run's log read by the Python package (afford.read_log), which decodes each message
on its own (python/afford/logs.py): the same messages per channel, in order, each at its place
in the run (docs/watching.md: the time the log gives the run's RUN_CONFIG, a millisecond a step,
a microsecond a message within its step), with the same field values, each image field's PNG
the message's pixels; the scene and focus images byte for byte, and each FORWARD_PREDICTION's
predicted images (as round(255 v)) side by side, on their image topics at their messages' times,
where the messages' SCENE.data, FOCUS.image and FORWARD_PREDICTION.what name those topics (each
image once in the file); a gaze box per FOCUS and EFFECT where the focus window is.

    compare.py LOG CHECKER_OUTPUT.jsonl AFFORD_BINARY
"""
import base64
import json
import math
import subprocess
import sys

import numpy as np

import afford


def fail(what):
    sys.exit(f"compare.py: {what}")


def flat(v):
    """A nested JSON list as one flat list."""
    return [x for e in v for x in flat(e)] if isinstance(v, list) else [v]


def same(want, got, path):
    """A field as the Python package has it (want) against its JSON (got)."""
    if isinstance(want, dict):
        if not isinstance(got, dict) or set(want) != set(got):
            fail(f"{path}: fields {sorted(want)} against {sorted(got) if isinstance(got, dict) else got!r}")
        for k in want:
            same(want[k], got[k], f"{path}.{k}")
    elif isinstance(want, np.ndarray) and want.dtype == np.uint8:
        # Bytes: a base64 string, or a list of them (one per entry of the first dimension).
        rows = [got] if isinstance(got, str) else got
        parts = [want] if isinstance(got, str) else list(want)
        if len(rows) != len(parts) or any(base64.b64decode(r, validate=True) != p.tobytes() for r, p in zip(rows, parts)):
            fail(f"{path}: bytes differ")
    elif isinstance(want, np.ndarray):
        values = flat(got)
        kind = np.float64 if want.dtype.kind == "f" else want.dtype
        if len(values) != want.size or not np.array_equal(np.asarray(values, dtype=kind), want.reshape(-1).astype(kind)):
            fail(f"{path}: {want.dtype} array of {want.shape} differs")
        if want.ndim > 1 and len(got) != want.shape[0]:
            fail(f"{path}: {len(got)} rows, not {want.shape[0]}")
    elif isinstance(want, list):
        if not isinstance(got, list) or len(want) != len(got):
            fail(f"{path}: a list of {len(want)} against {got!r:.60}")
        for i, (w, g) in enumerate(zip(want, got)):
            same(w, g, f"{path}[{i}]")
    elif isinstance(want, bool) or isinstance(got, bool):
        if want is not got:
            fail(f"{path}: {want!r} against {got!r}")
    elif isinstance(want, float):
        if not isinstance(got, (int, float)) or float(got) != want:
            fail(f"{path}: {want!r} against {got!r}")
    elif type(want) is not type(got) or want != got:
        fail(f"{path}: {want!r} against {got!r}")


# The image fields, written as PNG (experiment/export/image_fields.hpp).
IMAGE_FIELDS = {"FOCUS": ("diff_image",), "EFFECT": ("image",), "FORWARD_QUERY": ("image",), "GOAL": ("image",),
                "PROBE": ("images",)}
# The fields whose pixels are on an image topic, which they name ("" for none): check_images compares them.
MOVED_FIELDS = {"SCENE": ("data", "/SCENE/image"), "FOCUS": ("image", "/FOCUS/image"),
                "FORWARD_PREDICTION": ("what", "/FORWARD_PREDICTION/what")}


def as_bytes(values):
    """Predicted pixels (float32 in [0, 1]) as the export writes them: round(255 v), halves away from zero."""
    scaled = np.clip(values.astype(np.float32), 0, 1) * np.float32(255)  # (float32 arithmetic, as in C++)
    return np.floor(scaled.astype(np.float64) + 0.5).astype(np.uint8)


def same_images(want, got, path):
    """An image field (side x side x 3 arrays, one or a list of them) against its PNGs (base64, "" for none)."""
    if want.size == 0:
        if got not in ("", []):
            fail(f"{path}: no image, but {got!r:.40}")
        return
    if want.ndim == 3:
        want, got = want[None], [got]
    if not isinstance(got, list) or len(got) != len(want):
        fail(f"{path}: {len(want)} images against {got!r:.40}")
    for k, (w, g) in enumerate(zip(want, got)):
        if png_pixels(g).shape != w.shape or not (png_pixels(g) == w).all():
            fail(f"{path}[{k}]: the PNG's pixels are not the message's")


def round_half_away(v):
    """afford's roundHalfAway (common/src/image.cpp): C's round of v cleared of noise below 1e-9."""
    def c_round(x):
        f = math.floor(abs(x))
        return math.copysign(f + 1 if abs(x) - f >= 0.5 else f, x)
    return c_round(c_round(v * 1e9) / 1e9)


def stamp(m):
    return m["timestamp"]["sec"] * 1_000_000_000 + m["timestamp"]["nsec"]


def main(log_path, lines_path, afford_bin):
    types = channel_types(afford_bin)
    with open(lines_path) as f:
        lines = [json.loads(line) for line in f]
    totals = lines.pop()["totals"]
    if not totals["ok"] or totals["messages"] != len(lines):
        fail(f"the checker's totals: {totals}")
    topics = {}
    for line in lines:
        topics.setdefault(line["topic"], []).append(line)
    log = afford.read_log(log_path)
    if log.refused or log.unknown_channels or log.malformed:
        fail(f"the log has refused, unknown or malformed events: {log!r}")
    by_channel = {}
    for m in log:
        by_channel.setdefault(m.channel, []).append(m)
    channels = {t for t in topics if not t.startswith("/")}
    if channels != set(by_channel):
        fail(f"channels {sorted(channels)} against the log's {sorted(by_channel)}")
    times = places(log)
    for channel, messages in by_channel.items():
        exported = topics[channel]
        if len(exported) != len(messages):
            fail(f"{channel}: {len(exported)} messages exported, {len(messages)} in the log")
        for i, (m, e) in enumerate(zip(messages, exported)):
            if e["log_time"] != times[id(m)] or e["publish_time"] != e["log_time"] or e["sequence"] != i:
                fail(f"{channel}[{i}] of step {m['step']}: times {e['log_time']}, {e['publish_time']}, "
                     f"not its place {times[id(m)]}")
            if e["schema"] != f"afford.{types[channel]}":
                fail(f"{channel}: schema {e['schema']}")
            fields, got = dict(m.fields), dict(e["message"])
            if channel == "SCENE":
                del fields["image"]  # the scene decoded: its PNG, below
            if channel in MOVED_FIELDS:
                name, topic = MOVED_FIELDS[channel]
                if got.pop(name, None) != (topic if fields.pop(name).size else ""):
                    fail(f"{channel}[{i}].{name} does not name {topic}")
            for name in IMAGE_FIELDS.get(channel, ()):
                same_images(fields.pop(name), got.pop(name, None), f"{channel}[{i}].{name}")
            same(fields, got, f"{channel}[{i}]")
    check_images(log, topics)
    counts = ", ".join(f"{c} {len(by_channel[c])}" for c in sorted(by_channel))
    print(f"{log_path}: every message of the log is in the MCAP file as the Python package decodes it ({counts}), "
          f"with {len(topics.get('/SCENE/image', []))} scene images, {len(topics.get('/FOCUS/image', []))} focus "
          f"images, {len(topics.get('/FORWARD_PREDICTION/what', []))} images of predictions and "
          f"{len(topics.get('/SCENE/gaze', []))} gaze boxes, every image field's PNG the message's pixels")


def places(log):
    """Each message's time in the file (by id), from its place in the run: the log's messages come in step order."""
    extrinsic = "phase: extrinsic" in log.config_yaml.splitlines()
    start = log.messages[0].utime * 1000  # the run's RUN_CONFIG
    times, at, place, last = {}, None, 0, -1
    for m in log:
        step = m["step"]
        if m.channel == "RUN_CONFIG" or (m.channel == "RUN_CONTROL" and m["command"] == 1):  # START
            step = -1
        elif m.channel == "RUN_CONTROL":  # STOP
            step = last + 1
        elif m.channel == "EFFECT" and not extrinsic:  # seen on the scene of the step after its action
            step += 1
        place = place + 1 if step == at else 0
        at, last = step, max(last, step)
        times[id(m)] = start + (step + 1) * 1_000_000 + min(place, 999) * 1_000
    return times


def channel_types(afford_bin):
    """Each channel's message type, from the protocol's table (`afford processes --protocol`)."""
    out = subprocess.run([afford_bin, "processes", "--protocol"], check=True, capture_output=True, text=True).stdout
    types = {}
    for row in out.splitlines():
        cells = [c.strip().strip("`") for c in row.split("|")]
        if len(cells) > 3 and cells[2].endswith("_t"):
            types[cells[1]] = cells[2]
    return types


def png_pixels(data):
    """A foxglove.CompressedImage's PNG (base64) as height x width x 3 bytes."""
    import io
    import matplotlib.image
    img = matplotlib.image.imread(io.BytesIO(base64.b64decode(data)), format="png")
    return np.rint(img[:, :, :3] * 255).astype(np.uint8)


def check_images(log, topics):
    """Each SCENE's and FOCUS's image byte for byte, each FORWARD_PREDICTION's predicted images side by side; a
    gaze box per FOCUS and EFFECT, in log order."""
    scenes, focus, gaze, predicted = (topics.get(t, []) for t in ("/SCENE/image", "/FOCUS/image", "/SCENE/gaze",
                                                                  "/FORWARD_PREDICTION/what"))
    times = places(log)
    size = None
    n = {"SCENE": 0, "FOCUS": 0, "EFFECT": 0, "FORWARD_PREDICTION": 0}
    for m in log:
        if m.channel == "FORWARD_PREDICTION" and m["n_actions"]:
            image = predicted[n["FORWARD_PREDICTION"]]["message"]
            if image["format"] != "png" or stamp(image) != times[id(m)] or \
                    not np.array_equal(png_pixels(image["data"]), np.concatenate(list(as_bytes(m["what"])), axis=1)):
                fail(f"/FORWARD_PREDICTION/what[{n['FORWARD_PREDICTION']}] is not its message's predictions")
            n[m.channel] += 1
        if m.channel not in n or m.channel == "FORWARD_PREDICTION" or (m.channel != "SCENE" and size is None):
            continue  # (a gaze before any scene: none in a run's log)
        if m.channel == "SCENE":
            image = scenes[n["SCENE"]]["message"]
            size = (m["width"], m["height"])
            if image["format"] != "png" or not (png_pixels(image["data"]) == m["image"]).all() \
                    or stamp(image) != times[id(m)]:
                fail(f"/SCENE/image[{n['SCENE']}] is not SCENE[{n['SCENE']}]'s image")
        if m.channel == "FOCUS":
            image = focus[n["FOCUS"]]["message"]
            if image["format"] != "png" or not (png_pixels(image["data"]) == m["image"]).all() \
                    or stamp(image) != times[id(m)]:
                fail(f"/FOCUS/image[{n['FOCUS']}] is not FOCUS[{n['FOCUS']}]'s image")
        if m.channel in ("FOCUS", "EFFECT"):
            box = gaze[n["FOCUS"] + n["EFFECT"]]["message"]["points"][0]
            x, y = (m["x"], m["y"]) if m.channel == "FOCUS" else (m["after_x"], m["after_y"])
            left, top = round_half_away(x * size[0] - m["side"] / 2), round_half_away(y * size[1] - m["side"] / 2)
            if box["type"] != 2 or box["points"][0] != {"x": left, "y": top} or \
                    box["points"][2] != {"x": left + m["side"], "y": top + m["side"]} or stamp(box) != times[id(m)]:
                fail(f"the gaze box of {m.channel} of step {m['step']}: {box['points']}, not at ({left}, {top})")
        n[m.channel] += 1
    if (len(scenes), len(focus), len(gaze), len(predicted)) != \
            (n["SCENE"], n["FOCUS"], n["FOCUS"] + n["EFFECT"], n["FORWARD_PREDICTION"]):
        fail(f"{len(scenes)} scene images, {len(focus)} focus images, {len(gaze)} gaze boxes, {len(predicted)} "
             f"predictions for {n}")


if __name__ == "__main__":
    main(*sys.argv[1:])
