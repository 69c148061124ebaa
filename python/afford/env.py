"""A Gymnasium-style environment over afford's environment and eye cores, in process.

    from afford.env import AffordEnv
    env = AffordEnv(world="base", seed=1)
    obs, info = env.reset(seed=1)
    obs, reward, terminated, truncated, info = env.step({"act": 2, "look": [-1, -1]})

Each step is one step of the agent's loop (paper Algorithm 1) without the
predictors: the eye's bottom-up scan has picked an object (the observation's
`focus` and `gaze`), or the action says where to look instead; the action
is executed on the object in focus; the eye sees its effect; then the next
step's scan. The interface is Gymnasium's (reset(seed=), step, spaces,
render); Gymnasium itself is not needed (not packaged in Debian): without
it, the spaces are small classes of this module with the same methods, and
with it they are gymnasium.spaces and the environment is registered as
"afford/Affordances-v0".
"""
from __future__ import annotations

from typing import Any, Callable

import numpy as np

from . import _afford

try:  # optional
    import gymnasium
    from gymnasium import spaces as _spaces
except ImportError:  # pragma: no cover - the Debian setup has no gymnasium
    gymnasium = None
    _spaces = None


class Box:
    """gymnasium.spaces.Box's interface, for when Gymnasium is absent."""

    def __init__(self, low, high, shape, dtype):
        self.low, self.high, self.shape, self.dtype = low, high, tuple(shape), np.dtype(dtype)
        self._rng = np.random.default_rng()

    def seed(self, seed=None):
        self._rng = np.random.default_rng(seed)

    def sample(self):
        if np.issubdtype(self.dtype, np.integer):
            return self._rng.integers(self.low, self.high, self.shape, dtype=self.dtype, endpoint=True)
        return self._rng.uniform(self.low, self.high, self.shape).astype(self.dtype)

    def contains(self, x) -> bool:
        x = np.asarray(x)
        return x.shape == self.shape and bool(np.all(x >= self.low)) and bool(np.all(x <= self.high))

    def __repr__(self):
        return f"Box({self.low}, {self.high}, {self.shape}, {self.dtype})"


class Discrete:
    """gymnasium.spaces.Discrete's interface, for when Gymnasium is absent."""

    def __init__(self, n: int):
        self.n, self.shape, self.dtype = n, (), np.dtype(np.int64)
        self._rng = np.random.default_rng()

    def seed(self, seed=None):
        self._rng = np.random.default_rng(seed)

    def sample(self) -> int:
        return int(self._rng.integers(self.n))

    def contains(self, x) -> bool:
        return isinstance(x, (int, np.integer)) and 0 <= int(x) < self.n

    def __repr__(self):
        return f"Discrete({self.n})"


class Dict:
    """gymnasium.spaces.Dict's interface, for when Gymnasium is absent."""

    def __init__(self, spaces: dict[str, Any]):
        self.spaces = spaces

    def seed(self, seed=None):
        for i, s in enumerate(self.spaces.values()):
            s.seed(None if seed is None else seed + i)

    def sample(self) -> dict[str, Any]:
        return {k: s.sample() for k, s in self.spaces.items()}

    def contains(self, x) -> bool:
        return isinstance(x, dict) and x.keys() == self.spaces.keys() and all(
            s.contains(x[k]) for k, s in self.spaces.items())

    def __getitem__(self, key):
        return self.spaces[key]

    def __repr__(self):
        return f"Dict({self.spaces})"


def _box(low, high, shape, dtype):
    return _spaces.Box(low, high, shape, dtype) if _spaces else Box(low, high, shape, dtype)


def _discrete(n):
    return _spaces.Discrete(n) if _spaces else Discrete(n)


def _dict(d):
    return _spaces.Dict(d) if _spaces else Dict(d)


PASS = 4  # the action that does nothing

GAZE_COLOUR = (255, 255, 0)  # yellow, as afford-viewer's gaze box


def gaze_box(scene: np.ndarray, gaze, side: int) -> np.ndarray:
    """A copy of `scene` (H x W x 3) with a one-pixel frame around the side x side window centred at
    `gaze` ((x, y) in [0, 1], y down the rows), drawn just outside the window; clipped at the edges."""
    out = np.array(scene, copy=True)
    height, width = out.shape[:2]
    cx, cy = int(round(float(gaze[0]) * width)), int(round(float(gaze[1]) * height))
    left, top = cx - side // 2 - 1, cy - side // 2 - 1
    right, bottom = left + side + 1, top + side + 1
    rows, cols = slice(max(top, 0), min(bottom, height - 1) + 1), slice(max(left, 0), min(right, width - 1) + 1)
    for r in (top, bottom):
        if 0 <= r < height:
            out[r, cols] = GAZE_COLOUR
    for c in (left, right):
        if 0 <= c < width:
            out[rows, c] = GAZE_COLOUR
    return out


class AffordEnv(gymnasium.Env if gymnasium else object):
    """The world of an experiment (its objects, affordances and eye), a step at a time.

    world: an experiment of config/experiments (its world: objects, table,
    late objects) or an experiment file; seed: the run's seed (the objects'
    places, the eye's noise and the actions' outcomes are drawn from it);
    set: config keys and values; scenario: an extrinsic scenario
    (config/scenarios), whose initial state the world starts in and whose goal
    image is in info["goal"] at reset; reward: "success" (1 when the action's
    effect happened, else 0), "goal" (minus the scene's distance to the
    scenario's goal; the episode terminates when it is below
    planner.success_distance), or a function of the step's info.

    Observation: {"scene": H x W x 3 uint8, "focus": side x side x 3 uint8,
    "gaze": (x, y) in [0, 1]}. Action: {"act": 0-3 (move, turn green, turn
    red, turn blue) or 4 (pass), "look": (x, y) in [0, 1] to look there
    first, or negative to act on what the scan found}. An episode is
    truncated after the experiment's run.steps steps.
    """

    metadata = {"render_modes": ["rgb_array"]}

    def __init__(self, world: str = "base", seed: int = 0, system: str = "IMP", set: dict[str, Any] | None = None,
                 scenario: str | None = None, reward: str | Callable[[dict[str, Any]], float] = "success",
                 render_mode: str | None = None):
        if reward not in ("success", "goal") and not callable(reward):
            raise ValueError(f"reward {reward!r}: 'success', 'goal' or a function of the step's info")
        if reward == "goal" and not scenario:
            raise ValueError("reward 'goal' needs a scenario")
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode {render_mode!r}: None or 'rgb_array'")
        self._args = (world, system, [f"{k}={v}" for k, v in (set or {}).items()], scenario or "")
        self._reward = reward
        self.render_mode = render_mode
        self._seed = seed
        self._world = _afford.World(world, system, seed, self._args[2], self._args[3])
        size, side = self._world.scene_size, self._world.focus_side
        self.observation_space = _dict({
            "scene": _box(0, 255, (size, size, 3), np.uint8),
            "focus": _box(0, 255, (side, side, 3), np.uint8),
            "gaze": _box(0.0, 1.0, (2,), np.float64),
        })
        self.action_space = _dict({"act": _discrete(PASS + 1), "look": _box(-1.0, 1.0, (2,), np.float64)})

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        if seed is not None and seed != self._seed:
            self._seed = seed
            world, system, settings, scenario = self._args
            self._world = _afford.World(world, system, seed, settings, scenario)
        else:
            self._world.reset()
        if gymnasium:
            super().reset(seed=seed)
        self.action_space.seed(self._seed)
        info = {"step": 0}
        if self._args[3]:
            info["goal"] = self._world.goal()
        return self._world.observation(), info

    def step(self, action: dict[str, Any]):
        act = int(action["act"])
        look = action.get("look")
        x, y = (-1.0, -1.0) if look is None else (float(look[0]), float(look[1]))
        info = self._world.step(act, x, y)
        if callable(self._reward):
            reward = float(self._reward(info))
        elif self._reward == "goal":
            reward = -info["goal_distance"]
        else:
            reward = 1.0 if info["succeeded"] else 0.0
        terminated = self._reward == "goal" and info["goal_distance"] < self._world.success_distance
        truncated = self._world.step_count >= self._world.steps
        return self._world.observation(), reward, terminated, truncated, info

    def render(self):
        """With render_mode "rgb_array": the scene with the gaze box (yellow, as afford-viewer draws it),
        a frame just outside the focus window the eye looks through."""
        if self.render_mode != "rgb_array":
            return None
        obs = self._world.observation()
        return gaze_box(obs["scene"], obs["gaze"], self._world.focus_side)

    def close(self):
        pass


if gymnasium:  # pragma: no cover
    gymnasium.register(id="afford/Affordances-v0", entry_point="afford.env:AffordEnv")
