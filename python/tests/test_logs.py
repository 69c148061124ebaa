"""afford.read_log: a run's messages through the project's log reader and the edge's checks."""
import json
import shutil
import subprocess
import warnings

import numpy as np
import pytest

import afford


def run_of(made):
    s = json.loads((made / "base" / "summary.json").read_text())
    return s["systems"]["IMP"]["runs"][0]


def test_a_runs_messages_come_by_channel_with_images_as_arrays(made):
    run = run_of(made)
    log = afford.read_log(made / "logs" / run["run_id"])
    assert log.run_id == run["run_id"]
    assert log.refused == log.unknown_channels == log.malformed == log.torn_bytes == 0
    assert "steps: 400" in log.config_yaml
    decisions = log.channel("DECISION")
    assert [d["step"] for d in decisions] == list(range(400))
    acted = [d for d in decisions if d["acted"]]
    assert len(acted) == sum(run["actions_executed"])
    scene = log.channel("SCENE")[0]
    assert scene["image"].shape == (scene["height"], scene["width"], 3)
    assert scene["image"].dtype == np.uint8
    focus = log.channel("FOCUS")[0]
    assert focus["image"].shape == (focus["side"], focus["side"], 3)
    # the final table of the run's last AFFORDANCE_TABLE is the summary's
    table = log.channel("AFFORDANCE_TABLE")[-1]
    assert np.allclose(table["affordance"], np.array(run["affordance"]))
    assert log.channel("RESULT")[0]["weights_checksum"] == run["weights_checksum"]
    frame = log.frame("DECISION")
    assert len(frame) == 400 and {"step", "acted", "action", "motivation"} <= set(frame.columns)


def test_a_message_is_a_mapping_of_its_fields_and_its_repr_is_short(made):
    focus = afford.read_log(made / "logs" / run_of(made)["run_id"], channels=["FOCUS"]).messages[0]
    assert dict(focus) == focus.fields and set(focus.keys()) == set(focus.fields) and len(focus) == len(focus.fields)
    assert dict(focus.items())["step"] == focus["step"] and focus.get("nothing", 7) == 7 and "image" in focus
    text = repr(focus)
    assert text.startswith("Message(FOCUS, utime=") and "image=<uint8 array 21x21x3>" in text and len(text) < 600
    with pytest.raises(KeyError, match="FOCUS has no field 'nothing'"):
        focus["nothing"]


def test_channels_keeps_only_those(made):
    log = afford.read_log(made / "logs" / run_of(made)["run_id"], channels=["DECISION"])
    assert {m.channel for m in log} == {"DECISION"}
    assert set(afford.channels()) >= {"SCENE", "FOCUS", "DECISION", "PREDICTION", "RUN_CONFIG"}


def test_a_damaged_log_is_read_as_far_as_it_goes(made, tmp_path):
    src = made / "logs" / run_of(made)["run_id"] / "log.00.lcm"
    data = bytearray(src.read_bytes())
    (tmp_path / "cut").mkdir()
    (tmp_path / "cut" / "log.00.lcm").write_bytes(bytes(data[: len(data) // 2]))
    with pytest.warns(afford.LogCutWarning):
        log = afford.read_log(tmp_path / "cut")
    assert log.torn_bytes > 0
    assert 0 < len(log) < len(afford.read_log(src))


def test_a_cut_log_is_never_read_as_the_whole_run(made, tmp_path):
    """A log cut on an event boundary, with its manifest beside it or not: read as far as it goes, with a warning
    and `cut` saying what is missing; replay does not call it equal to the record. The whole log: no warning."""
    run = made / "logs" / run_of(made)["run_id"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert afford.read_log(run).cut == []
    data = (run / "log.00.lcm").read_bytes()
    boundary = 0  # the first event boundary past a third of the log (an event: a 28-byte header, channel, data)
    while boundary < len(data) // 3:
        boundary += 28 + int.from_bytes(data[boundary + 20:boundary + 24], "big") + \
            int.from_bytes(data[boundary + 24:boundary + 28], "big")
    for manifest in (True, False):
        cut = tmp_path / f"cut-{manifest}"
        cut.mkdir()
        (cut / "log.00.lcm").write_bytes(data[:boundary])
        if manifest:
            shutil.copy(run / "manifest.json", cut)
        with pytest.warns(afford.LogCutWarning, match="steps missing"):
            log = afford.read_log(cut)
        assert log.torn_bytes == 0 and all("missing" in c for c in log.cut), log.cut
        assert any(c.startswith("the log ends at step ") and c.endswith(" steps missing") for c in log.cut), log.cut
        assert any(c.endswith(" events missing") for c in log.cut) == manifest, log.cut
        replayed = afford.replay(cut)
        assert not replayed["ok"] and replayed["cut"] == log.cut, replayed


def test_bad_logs_are_named(tmp_path):
    with pytest.raises(RuntimeError, match="no run log at"):
        afford.read_log(tmp_path / "nowhere")
    (tmp_path / "junk").mkdir()
    (tmp_path / "junk" / "log.00.lcm").write_bytes(b"not an LCM log")
    with pytest.raises(RuntimeError, match="no RUN_CONFIG"):
        afford.read_log(tmp_path / "junk")


def same_message(a, b):
    return a.channel == b.channel and a.fields.keys() == b.fields.keys() and all(
        np.array_equal(a[k], b[k]) if isinstance(a[k], np.ndarray) else a[k] == b[k] for k in a.fields)


def test_a_shuffled_log_reads_as_the_log_as_recorded(made, tmp_path):
    """The messages come in step order: the same whatever the log's interleaving of its channels."""
    from conftest import BIN
    run = made / "logs" / run_of(made)["run_id"]
    recorded = afford.read_log(run)
    assert [m.channel for m in recorded][:8] == ["RUN_CONFIG", "RUN_CONTROL", "PROBE", "SCENE", "FOCUS",
                                                 "AFFORDANCE_TABLE", "PREDICTION", "DECISION"]
    # The last with the RUN_CONFIG interleaved too (a logger writes it first; another tool may not).
    for window, segments, more in ((20, 1, []), (1000, 2, []), (50, 2, ["--move-config"])):
        copy = tmp_path / f"shuffled-{window}"
        r = subprocess.run([str(BIN / "shuffle-log"), str(run), str(copy), "--window", str(window),
                            "--segments", str(segments), *more], capture_output=True, text=True)
        assert r.returncode == 0, r.stdout + r.stderr
        log = afford.read_log(copy)
        assert len(log) == len(recorded)
        assert all(same_message(a, b) for a, b in zip(log, recorded)), f"window {window}: another order"
        for channel in ("SCENE", "DECISION", "EFFECT"):  # each row's values but the time the logger wrote it
            assert log.frame(channel).drop(columns="utime").equals(recorded.frame(channel).drop(columns="utime"))
