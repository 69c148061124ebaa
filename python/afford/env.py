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
with it they are gymnasium.spaces and the environments are registered as
"afford/Affordances-v0" and "afford/AffordancesFlat-v0".

For learners that take one discrete action and an image (PPO, DQN as
CleanRL or Stable-Baselines3 write them):

    from afford.env import FlatAffordEnv, AffordVectorEnv
    env = FlatAffordEnv(world="base", scenario="scenario1", reward="goal", grid=5)
    envs = AffordVectorEnv(16, world="base", scenario="scenario1", reward="goal", seed=1)

FlatAffordEnv's action is one integer: 0-4 act on what the eye's scan found
(4 passes), or look at the centre of a cell of a grid over the scene, then
act; its observation is one image: the scene, the eye's window as a mask
channel, and the goal when there is one. AffordVectorEnv steps many of them
(one world per seed) in one call of the C++ core, with the GIL released.
Every episode's return, length and time are in the info of its last step
(`info["episode"]`, as Gymnasium's RecordEpisodeStatistics reports them).
"""
from __future__ import annotations

import time
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
        return _refusal(self, x, "") is None

    def __repr__(self):
        return _text(self)


class Discrete:
    """gymnasium.spaces.Discrete's interface, for when Gymnasium is absent."""

    def __init__(self, n: int):
        self.n, self.start, self.shape, self.dtype = n, 0, (), np.dtype(np.int64)
        self._rng = np.random.default_rng()

    def seed(self, seed=None):
        self._rng = np.random.default_rng(seed)

    def sample(self) -> int:
        return int(self._rng.integers(self.n))

    def contains(self, x) -> bool:
        return _refusal(self, x, "") is None

    def __repr__(self):
        return _text(self)


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
        return _refusal(self, x, "") is None

    def __getitem__(self, key):
        return self.spaces[key]

    def __repr__(self):
        return _text(self)


class MultiDiscrete:
    """gymnasium.spaces.MultiDiscrete's interface (one Discrete(n) per entry), for when Gymnasium is absent."""

    def __init__(self, nvec):
        self.nvec = np.asarray(nvec, dtype=np.int64)
        self.start, self.shape, self.dtype = np.zeros_like(self.nvec), self.nvec.shape, np.dtype(np.int64)
        self._rng = np.random.default_rng()

    def seed(self, seed=None):
        self._rng = np.random.default_rng(seed)

    def sample(self):
        return self._rng.integers(0, self.nvec, dtype=np.int64)

    def contains(self, x) -> bool:
        return _refusal(self, x, "") is None

    def __repr__(self):
        return _text(self)


# ---- what an environment is given, against its spaces ----------------------------------------------------------

_KINDS: dict[type, str] = {}


def space_kind(space) -> str:
    """"Dict", "MultiDiscrete", "Discrete" or "Box": which of the spaces `space` is, Gymnasium's or this module's
    (known by what it holds; kept per class)."""
    kind = _KINDS.get(type(space))
    if kind is None:
        kind = _KINDS[type(space)] = ("Dict" if isinstance(getattr(space, "spaces", None), dict) else
                                      "MultiDiscrete" if hasattr(space, "nvec") else
                                      "Discrete" if hasattr(space, "n") else "Box")
    return kind


def _text(space) -> str:
    """A space as Gymnasium writes it: Discrete(41), Box(-1.0, 1.0, (2,), float64), Dict(act: ..., look: ...);
    MultiDiscrete([41] * 16) when its entries are alike."""
    kind = space_kind(space)
    if kind == "Dict":
        return "Dict(" + ", ".join(f"{k}: {_text(s)}" for k, s in space.spaces.items()) + ")"
    if kind == "MultiDiscrete":
        nvec = np.asarray(space.nvec)
        same = nvec.size > 1 and bool(np.all(nvec == nvec.flat[0]))
        return f"MultiDiscrete([{nvec.flat[0]}] * {nvec.size})" if same else f"MultiDiscrete({nvec.tolist()})"
    if kind == "Discrete":
        start = int(getattr(space, "start", 0))
        return f"Discrete({int(space.n)}{f', start={start}' if start else ''})"
    bound = [np.asarray(b) for b in (space.low, space.high)]
    low, high = (b.flat[0].item() if b.size and np.all(b == b.flat[0]) else b.tolist() for b in bound)
    return f"Box({low!r}, {high!r}, {tuple(space.shape)}, {np.dtype(space.dtype).name})"


def _integer(x) -> bool:
    """One integer: a Python int or a numpy integer (a bool is not one)."""
    return (isinstance(x, (int, np.integer)) and not isinstance(x, bool)) or (
        isinstance(x, np.ndarray) and x.shape == () and x.dtype.kind in "iu")


def _first(bad: np.ndarray, x: np.ndarray, low: np.ndarray, high: np.ndarray) -> str:
    i = int(np.flatnonzero(bad)[0])
    more = f" ({int(bad.sum())} entries are outside)" if bad.sum() > 1 else ""
    return f"entry {i} ({x.flat[i].item()!r}) is not in [{low.flat[i].item()}, {high.flat[i].item()}]{more}"


def _within(a: np.ndarray, low, high) -> bool:
    """Every entry of `a` in [low, high] (not NaN); a few entries (an action's) compared as Python numbers, which
    is faster than numpy's comparisons of small arrays."""
    if a.size > 64:
        return bool((a >= low).all() and (a <= high).all())
    values = a.ravel().tolist()
    if isinstance(low, np.ndarray) or isinstance(high, np.ndarray):  # (Gymnasium's bounds: one per entry)
        return all(lo <= v <= hi for v, lo, hi in zip(values, np.broadcast_to(low, a.shape).ravel().tolist(),
                                                       np.broadcast_to(high, a.shape).ravel().tolist()))
    for v in values:
        if not low <= v <= high:
            return False
    return True


def _why(space, x) -> tuple[type[Exception], str] | None:
    """Why `x` is not in `space` (the error to raise, and why), or None when it is (a Dict's parts aside: _refusal):
    Discrete takes one integer; MultiDiscrete an array (or list) of integers of its shape; Box an array of real
    numbers of its shape that its dtype holds; each within its bounds. As Gymnasium's `contains`, but stricter on
    integers: its Discrete takes True (as 1), its MultiDiscrete takes 2.5."""
    kind = space_kind(space)
    if kind == "Dict":
        if not isinstance(x, dict):
            return TypeError, f"not a dict ({type(x).__name__})"
        if x.keys() != space.spaces.keys():
            return ValueError, f"its keys are {list(x)}, the space's {list(space.spaces)}"
        return None
    if kind == "MultiDiscrete":
        a = np.asarray(x) if isinstance(x, (list, tuple)) else x
        if not isinstance(a, np.ndarray) or a.dtype.kind not in "iu":
            of = f" of {a.dtype}" if isinstance(a, np.ndarray) else ""
            return TypeError, f"not integers ({type(x).__name__}{of})"
        nvec = np.asarray(space.nvec)
        if a.shape != nvec.shape:
            return ValueError, f"of shape {a.shape}, not {nvec.shape}"
        low = np.broadcast_to(np.asarray(getattr(space, "start", 0)), nvec.shape)
        bad = (a < low) | (a >= low + nvec)
        return (ValueError, _first(bad, a, low, low + nvec - 1)) if bad.any() else None
    if kind == "Discrete":
        if not _integer(x):
            return TypeError, f"not an integer ({type(x).__name__})"
        low = int(getattr(space, "start", 0))
        return None if low <= int(x) < low + int(space.n) else (ValueError, f"not in {low} to {low + int(space.n) - 1}")
    try:
        a = np.asarray(x)
    except (TypeError, ValueError):
        a = np.asarray(None)
    dtype = np.dtype(space.dtype)
    if a.dtype != dtype and (a.dtype.kind not in "iuf" or not np.can_cast(a.dtype, dtype)):
        of = f" of {a.dtype}" if a.dtype.kind != "O" else ""
        return TypeError, f"not numbers {dtype.name} holds ({type(x).__name__}{of})"
    if a.shape != tuple(space.shape):
        return ValueError, f"of shape {a.shape}, not {tuple(space.shape)}"
    if _within(a, space.low, space.high):
        return None
    low, high = (np.broadcast_to(np.asarray(b), a.shape) for b in (space.low, space.high))
    return ValueError, _first(~((a >= low) & (a <= high)), a, low, high)


def _shown(x) -> str:
    r = repr(x)
    return r if len(r) <= 120 else r[:117] + "..."


def _refusal(space, x, what: str) -> Exception | None:
    """The error naming the value and the space (the part of a Dict it fails in), or None when `x` is in `space`."""
    why = _why(space, x)
    if why is not None:
        return why[0](f"{what} {_shown(x)} is not in {_text(space)}: {why[1]}".lstrip())
    if space_kind(space) == "Dict":
        for key, part in space.spaces.items():
            if (e := _refusal(part, x[key], f"{what}[{key!r}]")) is not None:
                return e
    return None


def check_in(space, x, what: str = "action") -> None:
    """TypeError (not the kind of value the space holds) or ValueError (outside it) naming `what`, the value and the
    space, unless `x` is in `space`: every environment's check of what it is given, and its spaces' contains."""
    if (e := _refusal(space, x, what)) is not None:
        raise e


def _whole(x, what: str, low: int, high: int = 2**63 - 1, none: bool = False) -> None:
    """A whole number in [low, high] (None too, when `none`), given to a constructor or to reset."""
    if x is None and none:
        return
    if not _integer(x):
        raise TypeError(f"{what} {_shown(x)}: a whole number {low} to {high}{' or None' if none else ''}, not "
                        f"{type(x).__name__}")
    if not low <= int(x) <= high:
        raise ValueError(f"{what} {x}: a whole number {low} to {high}")


def _check_reset(seed, options, worlds: int = 1) -> None:
    """reset's seed (None, or one every world's seed, seed + i, is in range) and options (none taken)."""
    _whole(seed, "seed", 0, 2**63 - worlds, none=True)
    if options is not None and not isinstance(options, dict):
        raise TypeError(f"options {_shown(options)}: a dict or None (this environment takes no options)")
    if options:
        raise ValueError(f"options {_shown(options)}: this environment takes no reset options")


def _box(low, high, shape, dtype):
    return _spaces.Box(low, high, shape, dtype) if _spaces else Box(low, high, shape, dtype)


def _discrete(n):
    return _spaces.Discrete(n) if _spaces else Discrete(n)


def _dict(d):
    return _spaces.Dict(d) if _spaces else Dict(d)


def _multi_discrete(nvec):
    return _spaces.MultiDiscrete(nvec) if _spaces else MultiDiscrete(nvec)


PASS = 4  # the action that does nothing
_NO_LOOK = np.array([-1.0, -1.0])  # AffordEnv's look None: act on what the scan found

GAZE_COLOUR = (255, 255, 0)  # yellow, as afford-viewer's gaze box


def gaze_box(scene: np.ndarray, gaze, side: int) -> np.ndarray:
    """A copy of `scene` (H x W x 3) with a one-pixel frame around the side x side window centred at
    `gaze` ((x, y) in scene units: a pixel's column and row over the width, y down the rows), drawn just
    outside the window; clipped at the edges."""
    out = np.array(scene, copy=True)
    height, width = out.shape[:2]
    cx, cy = int(round(float(gaze[0]) * width)), int(round(float(gaze[1]) * width))
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
    "gaze": (x, y) in scene units (a pixel's column and row over the width)}.
    Action: {"act": 0-3 (the world's actions, `action_names`: move, turn
    green, turn red, turn blue in the paper's world; push, carry, topple,
    roll on the physical table) or 4 (pass), "look": (x, y) to look there
    first, or negative to act on what the scan found}. A table world
    (world.kind: table) is used on the thread that made it (its camera's
    OpenGL context). An episode is
    truncated after the experiment's run.steps steps. Its last step's info
    has "episode": {"r": its return, "l": its length, "t": seconds since its
    reset}, as Gymnasium's RecordEpisodeStatistics (1.0) reports them.
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
        _whole(seed, "seed", 0)
        self._args = (world, system, [f"{k}={v}" for k, v in (set or {}).items()], scenario or "")
        self._reward = reward
        self.render_mode = render_mode
        self._seed = seed
        self._world = _afford.World(world, system, seed, self._args[2], self._args[3])
        height, width, side = self._world.scene_height, self._world.scene_width, self._world.focus_side
        self.action_names = tuple(self._world.action_names)
        self.observation_space = _dict({
            "scene": _box(0, 255, (height, width, 3), np.uint8),
            "focus": _box(0, 255, (side, side, 3), np.uint8),
            "gaze": _box(0.0, 1.0, (2,), np.float64),
        })
        self.action_space = _dict({"act": _discrete(PASS + 1), "look": _box(-1.0, 1.0, (2,), np.float64)})

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        _check_reset(seed, options)
        if seed is not None and seed != self._seed:
            self._seed = seed
            world, system, settings, scenario = self._args
            self._world = _afford.World(world, system, seed, settings, scenario)
        else:
            self._world.reset()
        if gymnasium:
            super().reset(seed=seed)
        self.action_space.seed(self._seed)
        self._episode_return, self._episode_length, self._episode_start = 0.0, 0, time.perf_counter()
        info = {"step": 0}
        if self._args[3]:
            info["goal"] = self._world.goal()
        return self._world.observation(), info

    def step(self, action: dict[str, Any]):
        if isinstance(action, dict) and "look" in action and action["look"] is None:  # (act on what the scan found)
            action = {**action, "look": _NO_LOOK}
        check_in(self.action_space, action)
        look = action["look"]
        return self._step(int(action["act"]), float(look[0]), float(look[1]))

    def _step(self, act: int, x: float, y: float):
        info = self._world.step(act, x, y)
        if callable(self._reward):
            reward = float(self._reward(info))
        elif self._reward == "goal":
            reward = -info["goal_distance"]
        else:
            reward = 1.0 if info["succeeded"] else 0.0
        terminated = self._reward == "goal" and info["goal_distance"] < self._world.success_distance
        truncated = self._world.step_count >= self._world.steps
        self._episode_return += reward
        self._episode_length += 1
        if terminated or truncated:
            info["episode"] = {"r": self._episode_return, "l": self._episode_length,
                               "t": round(time.perf_counter() - self._episode_start, 6)}
        return self._observe(), reward, terminated, truncated, info

    def _observe(self):
        return self._world.observation()

    def render(self):
        """With render_mode "rgb_array": the scene with the gaze box (yellow, as afford-viewer draws it),
        a frame just outside the focus window the eye looks through."""
        if self.render_mode != "rgb_array":
            return None
        obs = self._world.observation()
        return gaze_box(obs["scene"], obs["gaze"], self._world.focus_side)

    def close(self):
        pass


def flat_action(action: int, grid: int, rows: float = 1.0) -> tuple[int, float, float]:
    """FlatAffordEnv's action `action` as (act, x, y): 0-4 act on what the scan found (x = y = -1); then, for
    each place of a grid x grid grid over the scene (row by row) and each act 0-3, look at the place's centre
    and act. Places are in scene units (over the scene's width): `rows` is the scene's height over its width
    (1 in the paper's world, 0.75 on the table's 320 x 240 camera). An action not in Discrete(5 + 4 grid^2)
    raises TypeError or ValueError naming the space."""
    _check_grid(grid)
    check_in(Discrete(PASS + 1 + 4 * int(grid) ** 2), action)
    return _afford.flat_action(int(action), int(grid), float(rows))


def flat_observation(scene: np.ndarray, gaze, side: int, goal: np.ndarray | None) -> np.ndarray:
    """One image (H x W x C, uint8): the scene's RGB, the eye's side x side window around the gaze as a mask
    channel (255 inside, clipped at the edges), and the goal's RGB when there is one (C = 7, else 4)."""
    return _afford.flat_observation(scene, (float(gaze[0]), float(gaze[1])), int(side), goal)


def _check_grid(grid) -> None:
    _whole(grid, "grid (places per side)", 1, 64)


class FlatAffordEnv(AffordEnv):
    """AffordEnv with one discrete action and one image, for learners that take those (CleanRL's and
    Stable-Baselines3's PPO and DQN; Stable-Baselines3 refuses Dict actions).

    Action: Discrete(5 + 4 * grid^2), see flat_action. Observation: Box (H, W, 4) uint8 (the scene and the
    eye's window as a mask), or (H, W, 7) with a scenario (and its goal image). The rest is AffordEnv's.
    """

    def __init__(self, world: str = "base", seed: int = 0, system: str = "IMP", set: dict[str, Any] | None = None,
                 scenario: str | None = None, reward: str | Callable[[dict[str, Any]], float] = "success",
                 render_mode: str | None = None, grid: int = 5):
        _check_grid(grid)
        super().__init__(world=world, seed=seed, system=system, set=set, scenario=scenario, reward=reward,
                         render_mode=render_mode)
        self.grid = int(grid)
        self.observation_space = _box(0, 255, (self._world.scene_height, self._world.scene_width, 7 if scenario else 4),
                                      np.uint8)
        self.action_space = _discrete(PASS + 1 + 4 * self.grid * self.grid)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        _, info = super().reset(seed=seed, options=options)
        return self._observe(), info

    def step(self, action: int):
        check_in(self.action_space, action)
        return self._step(*_afford.flat_action(int(action), self.grid, self._world.rows))

    def _observe(self):
        return self._world.flat_observation()


class AffordVectorEnv:
    """num_envs FlatAffordEnv worlds of one experiment stepped together by the C++ core (afford._afford.Worlds),
    with the GIL released, on `threads` threads: world i has seed seed + i, and goes exactly as
    FlatAffordEnv(seed=seed + i) does.

    Gymnasium's vector interface (0.29's autoreset): step(actions) returns arrays over the worlds; a world
    whose episode ended is reset in the same call, its next observation is its first, and its last
    observation and info are in info["final_observation"] and info["final_info"] (at its index; the mask
    info["_final_observation"]). info["episode"] = {"r", "l", "t"} arrays with the mask info["_episode"], as
    Gymnasium's RecordEpisodeStatistics writes them for a vector environment. reward: "success" or "goal".
    copy=False (as Gymnasium's SyncVectorEnv(copy=False)): the observations returned are an array the next
    step writes again, not a copy.
    """

    metadata = {"render_modes": []}

    def __init__(self, num_envs: int = 8, world: str = "base", seed: int = 0, system: str = "IMP",
                 set: dict[str, Any] | None = None, scenario: str | None = None, reward: str = "success",
                 grid: int = 5, threads: int = 1, copy: bool = True):
        if reward not in ("success", "goal"):
            raise ValueError(f"reward {reward!r}: 'success' or 'goal'")
        if reward == "goal" and not scenario:
            raise ValueError("reward 'goal' needs a scenario")
        _whole(num_envs, "num_envs", 1)
        _whole(seed, "seed", 0, 2**63 - int(num_envs))
        _whole(threads, "threads", 1, 1024)
        if not isinstance(copy, (bool, np.bool_)):
            raise TypeError(f"copy {_shown(copy)}: True or False")
        _check_grid(grid)
        self.num_envs, self.grid, self._reward = int(num_envs), int(grid), reward
        self._args = (world, system, [f"{k}={v}" for k, v in (set or {}).items()], scenario or "")
        self._threads, self._copy = int(threads), bool(copy)
        self._seed = seed
        self._make(seed)
        self.action_names = tuple(self._worlds.action_names)
        self.single_observation_space = _box(0, 255, (self._worlds.scene_height, self._worlds.scene_width,
                                                      7 if scenario else 4), np.uint8)
        self.single_action_space = _discrete(PASS + 1 + 4 * self.grid * self.grid)
        self.observation_space = _box(0, 255, (self.num_envs,) + self.single_observation_space.shape, np.uint8)
        self.action_space = _multi_discrete([self.single_action_space.n] * self.num_envs)

    def _make(self, seed: int):
        world, system, settings, scenario = self._args
        self._worlds = _afford.Worlds(world, system, [seed + i for i in range(self.num_envs)], settings, scenario,
                                      self._threads)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        _check_reset(seed, options, self.num_envs)
        if seed is not None and seed != self._seed:
            self._seed = seed
            self._make(seed)
        else:
            for i in range(self.num_envs):
                self._worlds.reset(i)
        self.action_space.seed(self._seed)
        self._returns = np.zeros(self.num_envs)
        self._lengths = np.zeros(self.num_envs, np.int64)
        self._starts = np.full(self.num_envs, time.perf_counter())
        return self._worlds.flat_observation(), {"step": np.zeros(self.num_envs, np.int64)}

    def step(self, actions):
        check_in(self.action_space, actions, "actions")
        obs, reward, terminated, truncated, info, final = self._worlds.step_flat(actions, self.grid,
                                                                                 self._reward == "goal")
        obs = obs.copy() if self._copy else obs
        self._returns += reward
        self._lengths += 1
        done = terminated | truncated
        if final is not None:
            now = time.perf_counter()
            info["episode"] = {"r": np.where(done, self._returns, 0.0), "l": np.where(done, self._lengths, 0),
                               "t": np.where(done, np.round(now - self._starts, 6), 0.0)}
            info["_episode"] = done.copy()
            info["final_observation"] = np.array(final + [None], dtype=object)[:-1]  # (an array of objects)
            info["_final_observation"] = done.copy()
            info["final_info"] = np.array(
                [{"episode": {"r": float(self._returns[i]), "l": int(self._lengths[i]),
                              "t": float(info["episode"]["t"][i])},
                  **{k: v[i] for k, v in info.items() if isinstance(v, np.ndarray) and v.shape == (self.num_envs,)
                     and not k.startswith("_")}} if done[i] else None for i in range(self.num_envs)], dtype=object)
            info["_final_info"] = done.copy()
            self._returns[done], self._lengths[done], self._starts[done] = 0.0, 0, now
        return obs, reward, terminated, truncated, info

    def close(self):
        pass


if gymnasium:  # pragma: no cover
    gymnasium.register(id="afford/Affordances-v0", entry_point="afford.env:AffordEnv")
    gymnasium.register(id="afford/AffordancesFlat-v0", entry_point="afford.env:FlatAffordEnv")
