"""afford.env.AffordEnv: Gymnasium's contract, the same trajectory for the same seed, and the agent's world."""
import numpy as np
import pytest

import afford
from afford.env import PASS, AffordEnv


def test_the_gymnasium_contract():
    env = AffordEnv(world="base", seed=1, set={"run.steps": 30})
    obs, info = env.reset(seed=1)
    assert isinstance(info, dict)
    assert env.observation_space.contains(obs)
    assert obs["scene"].shape == (150, 150, 3) and obs["focus"].shape == (21, 21, 3)
    truncated = False
    for t in range(30):
        action = env.action_space.sample()
        assert env.action_space.contains(action)
        obs, reward, terminated, truncated, info = env.step(action)
        assert env.observation_space.contains(obs)
        assert isinstance(reward, float) and reward in (0.0, 1.0) and reward == float(info["succeeded"])
        assert terminated is False and truncated == (t == 29)
    assert info["step"] == 29
    assert np.array_equal(env.render(), obs["scene"]) if env.render_mode else env.render() is None


def test_render_draws_the_gaze_box_around_the_focus_window():
    env = AffordEnv(world="base", seed=2, render_mode="rgb_array")
    obs, _ = env.reset(seed=2)
    frame = env.render()
    changed = np.any(frame != obs["scene"], axis=2)
    rows, cols = np.nonzero(changed)
    side = obs["focus"].shape[0]
    # a frame of side + 2 pixels around the gaze, in the viewer's yellow; the window inside it untouched
    assert rows.max() - rows.min() == side + 1 and cols.max() - cols.min() == side + 1
    assert abs((rows.max() + rows.min()) / 2 - obs["gaze"][1] * 150) <= 1
    assert abs((cols.max() + cols.min()) / 2 - obs["gaze"][0] * 150) <= 1
    assert np.all(frame[changed] == [255, 255, 0])
    inside = frame[rows.min() + 1:rows.max(), cols.min() + 1:cols.max()]
    assert np.array_equal(inside, obs["scene"][rows.min() + 1:rows.max(), cols.min() + 1:cols.max()])
    assert AffordEnv(world="base", seed=2).render() is None


def trajectory(seed, steps=60):
    env = AffordEnv(world="base", seed=0)
    obs, _ = env.reset(seed=seed)  # the action space is seeded from it too
    out = [obs]
    for _ in range(steps):
        obs, reward, *_ = env.step(env.action_space.sample())
        out.append(obs)
    return out


def test_the_same_seed_gives_the_same_trajectory():
    a, b, c = trajectory(5), trajectory(5), trajectory(6)
    assert all(np.array_equal(x["scene"], y["scene"]) and np.array_equal(x["gaze"], y["gaze"]) for x, y in zip(a, b))
    assert not all(np.array_equal(x["scene"], y["scene"]) for x, y in zip(a, c))


def test_fed_a_runs_decisions_it_sees_what_the_runs_eye_saw(made):
    """The processes' run and the environment agree step by step: the same gaze and focus image at every step."""
    log = afford.read_log(made / "logs" / "py-base-IMP-s1", channels=["FOCUS", "DECISION"])
    focus = {m["step"]: m for m in log.channel("FOCUS")}
    decisions = {m["step"]: m for m in log.channel("DECISION")}
    env = AffordEnv(world="base", seed=1, set={"run.steps": 400})
    obs, _ = env.reset(seed=1)
    successes = 0
    for t in range(400):
        assert np.allclose(obs["gaze"], [focus[t]["x"], focus[t]["y"]]), t
        assert np.array_equal(obs["focus"], focus[t]["image"]), t
        d = decisions[t]
        obs, reward, _, truncated, _ = env.step({"act": int(d["action"]) if d["acted"] else PASS, "look": None})
        successes += reward
    assert truncated
    run = afford.load(made / "base").runs.set_index("run_id").loc["py-base-IMP-s1"]
    assert successes == sum(run[f"successes[{a}]"] for a in afford.ACTIONS)


def test_a_scenario_gives_its_goal_and_the_goal_reward():
    env = AffordEnv(world="base", seed=1, scenario="scenario1", reward="goal")
    obs, info = env.reset()
    assert info["goal"].shape == obs["scene"].shape
    _, reward, terminated, _, info = env.step({"act": PASS, "look": None})
    assert reward == -info["goal_distance"] < 0 and not terminated
    custom = AffordEnv(world="base", seed=1, reward=lambda info: 2.0 if info["acted"] else -1.0)
    custom.reset()
    assert custom.step({"act": PASS, "look": None})[1] == -1.0


def test_bad_arguments_are_named():
    with pytest.raises(ValueError, match="reward 'goal' needs a scenario"):
        AffordEnv(reward="goal")
    with pytest.raises(ValueError, match="reward 'money'"):
        AffordEnv(reward="money")
    env = AffordEnv()
    env.reset()
    with pytest.raises(ValueError, match="action 7"):
        env.step({"act": 7, "look": None})
    with pytest.raises(ValueError):
        AffordEnv(world="no-such-world")
