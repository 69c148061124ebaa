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
