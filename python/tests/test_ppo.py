"""examples/ppo/ppo.py: PPO on AffordVectorEnv, reproducible from its seed."""
import json
import sys
from pathlib import Path

import pytest

pytest.importorskip("torch")
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "examples" / "ppo"))
import ppo  # noqa: E402

SMALL = ["--num-envs", "2", "--num-steps", "8", "--total-steps", "32", "--minibatches", "2", "--update-epochs", "1",
         "--episode-steps", "10", "--eval-every", "1", "--eval-episodes", "2"]


def test_the_same_seed_trains_the_same_agent_and_another_does_not(tmp_path):
    a = ppo.train(ppo.parse_args(SMALL + ["--seed", "3", "--out", str(tmp_path / "a")]))
    b = ppo.train(ppo.parse_args(SMALL + ["--seed", "3", "--out", str(tmp_path / "b")]))
    c = ppo.train(ppo.parse_args(SMALL + ["--seed", "4", "--out", str(tmp_path / "c")]))
    assert a["weights_checksum"] == b["weights_checksum"] != c["weights_checksum"]
    assert (tmp_path / "a" / "ppo_eval.csv").read_text().count("\n") == 4  # header, before training, 2 updates
    assert (tmp_path / "a" / "ppo_episodes.csv").read_text() == (tmp_path / "b" / "ppo_episodes.csv").read_text()
    result = json.loads((tmp_path / "a" / "ppo_result.json").read_text())
    assert result["env_steps"] == 32 and result["updates"] == 2


def test_without_out_it_writes_a_new_folder_in_the_temporary_directory_not_where_it_is_run(tmp_path, monkeypatch):
    import tempfile
    here, temporary = tmp_path / "checkout", tmp_path / "tmp"
    here.mkdir()
    temporary.mkdir()
    monkeypatch.chdir(here)
    monkeypatch.setattr(tempfile, "tempdir", str(temporary))
    result = ppo.train(ppo.parse_args(SMALL))
    out = Path(result["args"]["out"])
    assert out.parent == temporary and (out / "ppo_eval.csv").is_file()
    assert not list(here.iterdir())  # nothing where it was run


def test_compare_draws_the_figure_of_docs_ppo_again(tmp_path):
    import shutil
    import importlib.util  # examples/ppo/compare.py by its path: another example has a compare.py on sys.path too
    where = Path(__file__).resolve().parents[2] / "examples" / "ppo" / "compare.py"
    spec = importlib.util.spec_from_file_location("ppo_compare", where)
    compare = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(compare)
    docs = Path(__file__).resolve().parents[2] / "docs" / "ppo"
    shutil.copytree(docs, tmp_path / "ppo")
    figure = tmp_path / "ppo" / "fig_ppo_vs_planner.png"
    figure.unlink()
    assert compare.main(["--plot", "--out", str(tmp_path / "ppo")]) == 0
    assert figure.stat().st_size > 0
    # a folder without a scenario's evaluations is refused naming what it lacks; --plot without --out too
    (tmp_path / "ppo" / "ppo_eval_scenario2.csv").unlink()
    with pytest.raises(SystemExit, match="no evaluations of PPO on scenario2: neither ppo-scenario2/ppo_eval.csv"):
        compare.main(["--plot", "--out", str(tmp_path / "ppo")])
    with pytest.raises(SystemExit) as refused:
        compare.main(["--plot"])
    assert refused.value.code == 2
