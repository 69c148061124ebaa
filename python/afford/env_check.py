"""The environment contract, checked as Gymnasium's environment checker (gymnasium.utils.env_checker) checks it.

    from afford.env import FlatAffordEnv
    from afford.env_check import check_env
    check_env(FlatAffordEnv(world="base", seed=1))

Gymnasium is not packaged in Debian; these checks stand in for its checker
where it is absent (where it is installed, its own check_env can be run
too). Each failure raises AssertionError naming what was wrong.
"""
from __future__ import annotations

import inspect
from typing import Any

import numpy as np

from .env import space_kind


def _same(a: Any, b: Any) -> bool:
    """Observations equal, whatever their form (arrays, dicts of arrays, tuples)."""
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, (tuple, list)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    return np.array_equal(np.asarray(a), np.asarray(b))


def _check_space(space, what: str):
    for method in ("sample", "contains", "seed"):
        assert callable(getattr(space, method, None)), f"{what} has no {method}()"


def _check_obs(obs, space, where: str):
    assert space.contains(obs), f"the observation of {where} is not in the observation space {space!r}"
    if hasattr(space, "dtype") and isinstance(obs, np.ndarray) and space.dtype is not None:
        assert obs.dtype == space.dtype, f"the observation of {where} is {obs.dtype}, its space says {space.dtype}"


def _outside(space) -> list[tuple[Any, Any]]:
    """Values outside `space`, each with the space (a Dict's part) it is outside: for a Discrete, one past each
    end, a float, the text of an integer, None, a list, True; for a Box, a value of another shape, one past its
    upper bound, text; for a MultiDiscrete, one past the end, floats, another shape; for a Dict, each part's (the
    other parts sampled), a key missing, and not a dict."""
    kind = space_kind(space)
    if kind == "Dict":
        sample = space.sample()
        out = [({**sample, key: bad}, part) for key, s in space.spaces.items() for bad, part in _outside(s)]
        return out + [({k: v for k, v in list(sample.items())[1:]}, space), (0, space)]
    if kind == "MultiDiscrete":
        nvec = np.asarray(space.nvec)
        return [(nvec.copy(), space), (nvec * 0.5, space), (np.zeros(nvec.shape + (1,), np.int64), space)]
    if kind == "Discrete":
        low = int(getattr(space, "start", 0))
        return [(v, space) for v in (low + int(space.n), low - 1, low + 0.5, str(low), None, [low, low], True)]
    high = np.broadcast_to(np.asarray(space.high, dtype=np.float64), space.shape)
    return [(np.zeros(tuple(space.shape) + (1,)), space), (high + 1, space), (np.full(space.shape, "0"), space)]


def _rollout(env, seed: int, steps: int, first=None):
    obs, _ = env.reset(seed=seed)
    env.action_space.seed(seed)
    if first:
        first()
    out = [obs]
    for _ in range(steps):
        obs, reward, terminated, truncated, _ = env.step(env.action_space.sample())
        out.append((obs, reward, terminated, truncated))
        if terminated or truncated:
            break
    return out


def check_env(env, steps: int = 50, seed: int = 7) -> None:
    """Gymnasium's contract for a single environment:

    * observation_space and action_space are spaces (sample, contains, seed);
    * reset takes the keywords seed and options and returns (observation, info dict), the observation in
      its space and of its dtype;
    * reset(seed=s) twice, with the same actions, gives the same observations, rewards and ends; another
      seed gives another first observation or trajectory (the seed is used);
    * step returns (observation, reward, terminated, truncated, info): the observation in its space, the
      reward a real number, terminated and truncated booleans, info a dict; an action of
      action_space.sample() is taken; an episode's last info has "episode" with "r" (the sum of its
      rewards), "l" (its length) and "t";
    * an action outside the action space (of another kind, or out of its range or shape) is refused with
      TypeError or ValueError naming the space, and not taken (Gymnasium's checker does not check this);
    * render follows render_mode (None: returns None; "rgb_array": an H x W x 3 uint8 image), and
      metadata["render_modes"] lists the modes;
    * close() can be called.
    """
    _check_space(env.observation_space, "observation_space")
    _check_space(env.action_space, "action_space")
    params = inspect.signature(env.reset).parameters
    assert "seed" in params and "options" in params, "reset() does not take the keywords seed and options"
    result = env.reset(seed=seed)
    assert isinstance(result, tuple) and len(result) == 2, "reset() does not return (observation, info)"
    obs, info = result
    assert isinstance(info, dict), f"reset()'s info is {type(info).__name__}, not a dict"
    _check_obs(obs, env.observation_space, "reset()")

    # Steps, to the end of an episode.
    env.reset(seed=seed)
    env.action_space.seed(seed)
    total, length, ended = 0.0, 0, False
    while not ended:
        action = env.action_space.sample()
        assert env.action_space.contains(action), f"action_space.sample() gave {action!r}, not in the space"
        result = env.step(action)
        assert isinstance(result, tuple) and len(result) == 5, \
            "step() does not return (observation, reward, terminated, truncated, info)"
        obs, reward, terminated, truncated, info = result
        _check_obs(obs, env.observation_space, f"step {length}")
        assert isinstance(reward, (float, int, np.floating, np.integer)) and np.isfinite(reward), \
            f"step {length}: the reward {reward!r} is not a finite real number"
        assert isinstance(terminated, (bool, np.bool_)) and isinstance(truncated, (bool, np.bool_)), \
            f"step {length}: terminated and truncated are not booleans ({terminated!r}, {truncated!r})"
        assert isinstance(info, dict), f"step {length}: info is {type(info).__name__}, not a dict"
        total += float(reward)
        length += 1
        ended = bool(terminated or truncated)
        assert ended or "episode" not in info, f"step {length - 1}: info has 'episode' before the episode ended"
    episode = info.get("episode")
    assert isinstance(episode, dict) and {"r", "l", "t"} <= episode.keys(), \
        "the episode's last info has no 'episode' with 'r', 'l' and 't'"
    assert np.isclose(float(episode["r"]), total), f"info['episode']['r'] is {episode['r']}, the rewards sum to {total}"
    assert int(episode["l"]) == length, f"info['episode']['l'] is {episode['l']}, the episode took {length} steps"

    # Determinism by seed.
    a, b = _rollout(env, seed, steps), _rollout(env, seed, steps)
    assert len(a) == len(b), "reset(seed=) twice with the same actions: episodes of different lengths"
    assert _same(a[0], b[0]), "reset(seed=) twice: different first observations"
    for t, (x, y) in enumerate(zip(a[1:], b[1:])):
        assert _same(x[0], y[0]) and x[1:] == y[1:], f"reset(seed=) twice with the same actions: step {t} differs"
    # Refusals: an action outside the action space raises TypeError or ValueError naming the space (the part of a
    # Dict it is outside), and is not taken: the episode goes on as if it had not been given.
    refused = []

    def give_outside():
        for bad, part in outside:
            try:
                env.step(bad)
            except (TypeError, ValueError) as e:
                assert space_kind(part) in str(e), f"step({bad!r}) was refused without naming the space: {e}"
                refused.append(bad)
            else:
                raise AssertionError(f"step({bad!r}) was taken: it is not in the action space ({part!r})")
    outside = _outside(env.action_space)
    r = _rollout(env, seed, steps, first=give_outside)
    assert len(refused) == len(outside)
    assert len(r) == len(a) and all(_same(x, y) for x, y in zip([r[0]] + [x[0] for x in r[1:]],
                                                                [a[0]] + [x[0] for x in a[1:]])), \
        "after actions it refused, the episode went otherwise than without them"
    c = _rollout(env, seed + 1, steps)
    assert not all(_same(x if i == 0 else x[0], y if i == 0 else y[0]) for i, (x, y) in enumerate(zip(a, c))), \
        "another seed gives the same trajectory: the seed is not used"

    # Rendering.
    modes = getattr(env, "metadata", {}).get("render_modes")
    assert isinstance(modes, list), "metadata['render_modes'] is not a list"
    mode = getattr(env, "render_mode", None)
    assert mode is None or mode in modes, f"render_mode {mode!r} is not one of metadata['render_modes'] {modes}"
    frame = env.render()
    if mode is None:
        assert frame is None, "render() returned something with render_mode None"
    elif mode == "rgb_array":
        assert isinstance(frame, np.ndarray) and frame.ndim == 3 and frame.shape[2] == 3 and frame.dtype == np.uint8, \
            "render() with render_mode 'rgb_array' did not return an H x W x 3 uint8 image"
    env.close()
