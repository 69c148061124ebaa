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
    with pytest.raises(ValueError, match=r"action\['act'\] 7 is not in Discrete\(5\): not in 0 to 4"):
        env.step({"act": 7, "look": None})
    with pytest.raises(ValueError):
        AffordEnv(world="no-such-world")


# ---- the forms learners take: one discrete action, one image, batched; the contract as Gymnasium checks it ----

from afford.env import AffordVectorEnv, FlatAffordEnv, flat_action, flat_observation  # noqa: E402
from afford.env_check import check_env  # noqa: E402


@pytest.mark.parametrize("make", [
    lambda: AffordEnv(world="base", seed=1, set={"run.steps": 30}),
    lambda: AffordEnv(world="base", seed=1, set={"run.steps": 30}, render_mode="rgb_array"),
    lambda: FlatAffordEnv(world="base", seed=1, set={"run.steps": 30}),
    lambda: FlatAffordEnv(world="base", seed=1, set={"run.steps": 30}, scenario="scenario1", reward="goal", grid=3),
], ids=["dict", "dict-rendered", "flat", "flat-goal"])
def test_every_form_keeps_the_contract_gymnasiums_checker_checks(make):
    check_env(make())


class _Broken(FlatAffordEnv):
    def __init__(self, fault):
        super().__init__(world="base", seed=1, set={"run.steps": 10})
        self.fault = fault

    def step(self, action):
        obs, reward, terminated, truncated, info = super().step(action)
        if self.fault == "four":
            return obs, reward, terminated, info
        if self.fault == "episode":
            info.pop("episode", None)
        if self.fault == "reward":
            reward = float("nan")
        if self.fault == "observation":
            obs = obs[:, :, :3]
        return obs, reward, terminated, truncated, info


@pytest.mark.parametrize("fault, says", [("four", "does not return"), ("episode", "'episode'"),
                                         ("reward", "finite real"), ("observation", "not in the observation space")])
def test_the_checker_names_what_breaks_the_contract(fault, says):
    with pytest.raises(AssertionError, match=says):
        check_env(_Broken(fault))


def test_a_flat_action_is_an_act_on_what_the_scan_found_or_a_look_at_a_place_then_an_act():
    assert [flat_action(a, 3) for a in range(5)] == [(a, -1.0, -1.0) for a in range(5)]
    assert flat_action(5, 3) == (0, 1 / 6, 1 / 6)           # the first place, move
    assert flat_action(5 + 4 * 4 + 2, 3) == (2, 0.5, 0.5)   # the centre place (cell 4: row 1, column 1), turn red
    assert flat_action(5 + 4 * 9 - 1, 3) == (3, 5 / 6, 5 / 6)
    with pytest.raises(ValueError, match=r"action 41 is not in Discrete\(41\): not in 0 to 40"):
        flat_action(41, 3)
    with pytest.raises(TypeError, match=r"action 2.5 is not in Discrete\(41\): not an integer"):
        flat_action(2.5, 3)
    env = FlatAffordEnv(world="base", seed=2, grid=3)
    obs, _ = env.reset(seed=2)
    assert env.action_space.n == 41 and obs.shape == (150, 150, 4)
    obs, *_ = env.step(5 + 4 * 8 + 3)  # look at the last place, turn blue
    plain = AffordEnv(world="base", seed=2)
    plain.reset(seed=2)
    expected, *_ = plain.step({"act": 3, "look": [5 / 6, 5 / 6]})
    assert np.array_equal(obs[:, :, :3], expected["scene"])
    assert np.array_equal(obs, flat_observation(expected["scene"], expected["gaze"], 21, None))


def test_the_mask_channel_is_the_eyes_window():
    scene = np.zeros((150, 150, 3), np.uint8)
    obs = flat_observation(scene, (0.5, 0.2), 21, np.full((150, 150, 3), 9, np.uint8))
    rows, cols = np.nonzero(obs[:, :, 3])
    assert obs.shape == (150, 150, 7) and np.all(obs[:, :, 4:] == 9)
    assert (rows.min(), rows.max(), cols.min(), cols.max()) == (20, 40, 65, 85)
    corner = flat_observation(scene, (0.0, 1.0), 21, None)[:, :, 3]
    assert corner.sum() == 255 * 11 * 10  # clipped at the scene's edges


@pytest.mark.parametrize("threads", [1, 2])
def test_the_batched_env_goes_as_single_envs_of_the_same_seeds(threads):
    """16 worlds in one call against 16 FlatAffordEnv of the same seeds, over episodes that end and restart."""
    n, seed, steps = 16, 40, 25
    settings = {"run.steps": steps}
    vec = AffordVectorEnv(n, world="base", seed=seed, set=settings, grid=4, threads=threads)
    singles = [FlatAffordEnv(world="base", seed=seed + i, set=settings, grid=4) for i in range(n)]
    obs, _ = vec.reset(seed=seed)
    single_obs = [e.reset(seed=seed + i)[0] for i, e in enumerate(singles)]
    assert all(np.array_equal(obs[i], single_obs[i]) for i in range(n))
    rng = np.random.default_rng(3)
    returns, ended, changed = np.zeros(n), 0, 0
    for t in range(2 * steps + 5):
        actions = rng.integers(0, vec.single_action_space.n, n)
        obs, reward, terminated, truncated, info = vec.step(actions)
        for i, e in enumerate(singles):
            o, r, te, tr, inf = e.step(int(actions[i]))
            assert r == reward[i] and te == terminated[i] and tr == truncated[i], (t, i)
            returns[i] += r
            if te or tr:
                assert np.array_equal(info["final_observation"][i], o), (t, i)
                assert info["final_info"][i]["episode"]["r"] == inf["episode"]["r"] == returns[i]
                assert info["episode"]["l"][i] == inf["episode"]["l"] == steps and info["_episode"][i]
                o, _ = e.reset()
                returns[i], ended = 0.0, ended + 1
            changed += int(inf["image_changed"]) if "image_changed" in inf else 0
            assert np.array_equal(obs[i], o), (t, i)
    assert ended == 2 * n and changed > 0
    with pytest.raises(ValueError, match=r"actions array\(\[0, 0, 0\]\) is not in MultiDiscrete\(\[69\] \* 16\): "
                                         r"of shape \(3,\), not \(16,\)"):
        vec.step(np.zeros(3, np.int64))


# ---- what is outside an environment's spaces is refused, naming the space; what is inside is taken -------------

FLAT, VEC = "Discrete(21)", "MultiDiscrete([21] * 3)"  # (grid 2: 5 + 4 * 2 * 2 actions)
DICT_ACT, DICT_LOOK = "Discrete(5)", "Box(-1.0, 1.0, (2,), float64)"
OUTSIDE = [  # (env, action, error, what it says)
    ("flat", 2.5, TypeError, f"action 2.5 is not in {FLAT}: not an integer (float)"),
    ("flat", "3", TypeError, f"action '3' is not in {FLAT}: not an integer (str)"),
    ("flat", "move", TypeError, f"action 'move' is not in {FLAT}: not an integer (str)"),
    ("flat", None, TypeError, f"action None is not in {FLAT}: not an integer (NoneType)"),
    ("flat", [1, 2], TypeError, f"action [1, 2] is not in {FLAT}: not an integer (list)"),
    ("flat", True, TypeError, f"action True is not in {FLAT}: not an integer (bool)"),
    ("flat", np.float64(3.0), TypeError, f"action 3.0 is not in {FLAT}: not an integer (float64)"),
    ("flat", np.array([3]), TypeError, f"action array([3]) is not in {FLAT}: not an integer (ndarray)"),
    ("flat", 21, ValueError, f"action 21 is not in {FLAT}: not in 0 to 20"),
    ("flat", np.int64(-1), ValueError, f"action -1 is not in {FLAT}: not in 0 to 20"),
    ("dict", {"act": 2.5, "look": None}, TypeError, f"action['act'] 2.5 is not in {DICT_ACT}: not an integer (float)"),
    ("dict", {"act": "3", "look": None}, TypeError, f"action['act'] '3' is not in {DICT_ACT}: not an integer (str)"),
    ("dict", {"act": 5, "look": None}, ValueError, f"action['act'] 5 is not in {DICT_ACT}: not in 0 to 4"),
    ("dict", {"act": 2}, ValueError, "action {'act': 2} is not in Dict(act: Discrete(5), look: Box(-1.0, 1.0, (2,), "
                                     "float64)): its keys are ['act'], the space's ['act', 'look']"),
    ("dict", 2, TypeError, f"action 2 is not in Dict(act: {DICT_ACT}, look: {DICT_LOOK}): not a dict"),
    ("dict", {"act": 2, "look": [0.5, 2.0]}, ValueError,
     f"action['look'] [0.5, 2.0] is not in {DICT_LOOK}: entry 1 (2.0) is not in [-1.0, 1.0]"),
    ("dict", {"act": 2, "look": [float("nan"), 0.5]}, ValueError,
     f"action['look'] [nan, 0.5] is not in {DICT_LOOK}: entry 0 (nan) is not in [-1.0, 1.0]"),
    ("dict", {"act": 2, "look": 0.5}, ValueError, f"action['look'] 0.5 is not in {DICT_LOOK}: of shape (), not (2,)"),
    ("dict", {"act": 2, "look": ["a", "b"]}, TypeError,
     f"action['look'] ['a', 'b'] is not in {DICT_LOOK}: not numbers"),
    ("vec", [2.5, 1, 1], TypeError, f"actions [2.5, 1, 1] is not in {VEC}: not integers (list of float64)"),
    ("vec", ["3", "1", "1"], TypeError, f"actions ['3', '1', '1'] is not in {VEC}: not integers"),
    ("vec", "move", TypeError, f"actions 'move' is not in {VEC}: not integers (str)"),
    ("vec", None, TypeError, f"actions None is not in {VEC}: not integers (NoneType)"),
    ("vec", [1, 2], ValueError, f"actions [1, 2] is not in {VEC}: of shape (2,), not (3,)"),
    ("vec", np.array([[1, 2, 3]]), ValueError,
     f"actions array([[1, 2, 3]]) is not in {VEC}: of shape (1, 3), not (3,)"),
    ("vec", [1, 21, -1], ValueError, f"actions [1, 21, -1] is not in {VEC}: entry 1 (21) is not in [0, 20] "
                                     "(2 entries are outside)"),
]


def make(kind):
    env = {"flat": lambda: FlatAffordEnv(world="base", seed=3, grid=2),
           "dict": lambda: AffordEnv(world="base", seed=3),
           "vec": lambda: AffordVectorEnv(3, world="base", seed=3, grid=2)}[kind]()
    env.reset(seed=3)
    return env


@pytest.mark.parametrize("kind, action, error, says", OUTSIDE, ids=[f"{k}-{a!r}" for k, a, *_ in OUTSIDE])
def test_an_action_outside_the_space_is_refused_naming_the_space_and_the_value(kind, action, error, says):
    env, twin = make(kind), make(kind)
    with pytest.raises(error) as refused:
        env.step(action)
    assert str(refused.value).startswith(says), str(refused.value)
    space = env.action_space
    assert not space.contains({**action, "look": [-1.0, -1.0]} if isinstance(action, dict) and "look" in action
                              and action["look"] is None else action)  # (the space says the same)
    good = {"flat": 7, "dict": {"act": 1, "look": None}, "vec": [7, 0, 20]}[kind]  # nothing of it was taken:
    assert _same(env.step(good)[0], twin.step(good)[0])  # the next step as a twin's that was given none


def _same(a, b):
    return all(np.array_equal(a[k], b[k]) for k in a) if isinstance(a, dict) else np.array_equal(a, b)


@pytest.mark.parametrize("kind, actions", [
    ("flat", [7, np.int64(7), np.int32(7), np.uint8(7), np.array(7), 20, 0]),
    ("dict", [{"act": 1, "look": None}, {"act": np.int64(1), "look": [-1, -1]}, {"act": np.array(1), "look": None},
              {"act": 1, "look": np.array([-1.0, -0.5], np.float32)}, {"act": 4, "look": (0.5, 1)}]),
    ("vec", [[7, 0, 20], np.array([7, 0, 20]), np.array([7, 0, 20], np.uint8), (7, 0, 20)]),
])
def test_every_form_of_a_value_the_space_holds_is_taken_as_that_value(kind, actions):
    env = make(kind)
    for a in actions:
        twin = make(kind)
        plain = {"act": int(a["act"]), "look": None if a["look"] is None or a["look"][0] < 0 else
                 [float(a["look"][0]), float(a["look"][1])]} if kind == "dict" else (
            int(a) if kind == "flat" else [int(x) for x in a])
        env.reset(seed=3)
        assert _same(env.step(a)[0], twin.step(plain)[0]), a


@pytest.mark.parametrize("kind", ["flat", "dict", "vec"])
def test_reset_refuses_a_seed_or_options_it_does_not_take(kind):
    env = make(kind)
    top = 2**63 - (3 if kind == "vec" else 1)
    for seed, error, says in [(2.5, TypeError, "seed 2.5: a whole number 0 to"), ("3", TypeError, "seed '3'"),
                              (True, TypeError, "seed True"), (-1, ValueError, f"seed -1: a whole number 0 to {top}"),
                              (top + 1, ValueError, f"seed {top + 1}: a whole number 0 to {top}")]:
        with pytest.raises(error, match=f"^{says}"):
            env.reset(seed=seed)
    with pytest.raises(ValueError, match=r"options \{'render': True\}: this environment takes no reset options"):
        env.reset(options={"render": True})
    with pytest.raises(TypeError, match="options 'fast': a dict or None"):
        env.reset(options="fast")
    env.reset(seed=np.int64(4), options={})
    env.reset(seed=top, options=None)


def test_constructors_refuse_what_they_do_not_take():
    for make_it, error, says in [
            (lambda: AffordEnv(seed=1.5), TypeError, "seed 1.5: a whole number"),
            (lambda: FlatAffordEnv(grid=2.0), TypeError, r"grid \(places per side\) 2.0: a whole number 1 to 64"),
            (lambda: FlatAffordEnv(grid=65), ValueError, r"grid \(places per side\) 65: a whole number 1 to 64"),
            (lambda: AffordVectorEnv(True), TypeError, "num_envs True: a whole number 1 to"),
            (lambda: AffordVectorEnv(2, threads=1.5), TypeError, "threads 1.5: a whole number 1 to 1024"),
            (lambda: AffordVectorEnv(2, copy="no"), TypeError, "copy 'no': True or False"),
            (lambda: AffordVectorEnv(2, seed=2**63 - 1), ValueError, "seed 9223372036854775807: a whole number 0 to "
                                                                      "9223372036854775806")]:
        with pytest.raises(error, match=f"^{says}"):
            make_it()


# ---- the physical table (world.kind: table): MuJoCo, the camera, the hand ---------------------------------------

def test_the_table_world_goes_as_the_processes_table_run(tmp_path):
    """world="table": fed a table run's decisions, the environment and the eye of afford.env see what the run's
    eye saw at every step (the camera's 320 x 240 image, the gaze, the focus window), and its actions succeed as
    often as the run's did: one world, whichever runs it."""
    from conftest import afford as run_afford
    steps = 40
    run_afford("experiment", "table", "--system", "IMP", "--reps", "1", "--steps", str(steps), "--set",
               "table.truth.trials=2", "--run-prefix", "py", "--out", str(tmp_path / "out"), "--log-root",
               str(tmp_path / "logs"), cwd=tmp_path)
    log = afford.read_log(tmp_path / "logs" / "py-table-IMP-s1", channels=["FOCUS", "DECISION", "EFFECT"])
    focus = {m["step"]: m for m in log.channel("FOCUS")}
    decisions = {m["step"]: m for m in log.channel("DECISION")}
    env = AffordEnv(world="table", seed=1, set={"run.steps": steps})
    assert env.action_names == ("push", "carry", "topple", "roll")
    assert env.observation_space["scene"].shape == (240, 320, 3)
    obs, _ = env.reset(seed=1)
    acted = 0
    for t in range(steps):
        assert np.allclose(obs["gaze"], [focus[t]["x"], focus[t]["y"]]), t
        assert np.array_equal(obs["focus"], focus[t]["image"]), t
        d = decisions[t]
        acted += int(d["acted"])
        obs, reward, _, truncated, info = env.step({"act": int(d["action"]) if d["acted"] else PASS, "look": None})
        assert env.observation_space.contains(obs)
    assert truncated and acted > 5


def test_table_worlds_batched_on_threads_go_as_single_worlds():
    """A table world's camera draws only on the thread that made it (its OpenGL context): the batched worlds
    keep each on a thread of its own, and on 1 or 3 threads they go as FlatAffordEnv of the same seeds; a world
    stepped from another thread is refused, saying why."""
    import threading
    n, seed, steps = 4, 7, 6
    settings = {"run.steps": steps}
    singles = [FlatAffordEnv(world="table", seed=seed + i, set=settings, grid=3) for i in range(n)]
    single_obs = [e.reset(seed=seed + i)[0] for i, e in enumerate(singles)]
    assert single_obs[0].shape == (240, 320, 4)
    rng = np.random.default_rng(5)
    actions = [rng.integers(0, singles[0].action_space.n, n) for _ in range(steps + 2)]
    expected = [[e.step(int(a[i]))[:2] for i, e in enumerate(singles)] for a in actions[:steps]]
    for threads in (1, 3):
        vec = AffordVectorEnv(n, world="table", seed=seed, set=settings, grid=3, threads=threads)
        obs, _ = vec.reset(seed=seed)
        assert vec.action_names == ("push", "carry", "topple", "roll") and obs.shape == (n, 240, 320, 4)
        assert all(np.array_equal(obs[i], single_obs[i]) for i in range(n)), threads
        for t in range(steps):
            obs, reward, terminated, truncated, info = vec.step(actions[t])
            for i in range(n):
                o, r = expected[t][i]
                assert r == reward[i] and np.array_equal(obs[i] if not truncated[i] else info["final_observation"][i],
                                                         o), (threads, t, i)
        assert truncated.all()
    env = AffordEnv(world="table", seed=1)
    env.reset()
    said = []
    other = threading.Thread(target=lambda: said.append(_error_of(lambda: env.step({"act": 0, "look": None}))))
    other.start()
    other.join()
    assert "the thread that made it" in said[0], said


def _error_of(f):
    try:
        f()
    except Exception as e:  # noqa: BLE001 - the message is what is tested
        return str(e)
    return "no error"


def test_a_table_flat_action_looks_at_a_place_of_the_wider_than_high_scene():
    """Places are scene units, a pixel's column and row over the width: the table's 320 x 240 image is 0.75 high,
    so the grid's places span that, and the eye's window is drawn where its gaze is."""
    assert flat_action(5 + 4 * 8, 3, rows=0.75) == (0, 5 / 6, 0.75 * 5 / 6)
    env = FlatAffordEnv(world="table", seed=2, grid=3)
    env.reset(seed=2)
    obs, *_ = env.step(5 + 4 * 8 + 2)  # look at the last place (bottom right), topple
    plain = AffordEnv(world="table", seed=2)
    plain.reset(seed=2)
    expected, *_ = plain.step({"act": 2, "look": [5 / 6, 0.75 * 5 / 6]})
    assert np.array_equal(obs, flat_observation(expected["scene"], expected["gaze"], 21, None))
    rows, cols = np.nonzero(obs[:, :, 3])  # the window around the next scan's gaze, both coordinates over the width
    gx, gy = expected["gaze"]
    assert abs((rows.min() + rows.max()) / 2 - gy * 320) <= 1 and abs((cols.min() + cols.max()) / 2 - gx * 320) <= 1
    assert 0 < gy * 320 < 240 and gy * 320 - gy * 240 > 12, expected["gaze"]  # (a window placed by the height is off)
