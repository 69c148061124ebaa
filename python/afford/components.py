"""Components written in Python (docs/python.md#components-in-python).

A component is a class constructed with the run's configuration (a dict of
the run's whole configuration, config["motivation"]["leak"], with
experiment, system, seed, steps and motivation_kind at the top).

- A motivation's decide(percept) says, each step, whether to act and with
  which action.
- An affordance predictor's predict(image) says what each action affords the
  focused object and how fast that is changing (the learning progress), and
  learn(image, action, succeeded) learns from an executed action.

Either stands in for the shipped one in this process (afford.run(...,
motivation=Cls, affordance=Cls)) or as a process on the bus (python3 -m
afford.process motivation|predictors MODULE:CLASS). For exact replay and live
restart, its state must be a pure function of the calls it was given, in
order, and of the configuration; its randomness comes from
KeyedRng(config["seed"], step, sub), never from a clock or a global
generator.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

from . import _afford

ACTIONS = ("move", "turn green", "turn red", "turn blue")  # the action ids 0..3


@dataclass
class Decision:
    act: bool                 # act this step, or pass
    action: int = -1          # 0..3 (ACTIONS) when acting
    motivation: float = 0.0   # the signal, which DECISION reports
    threshold: float = 0.0    # ... and what it was compared with


class Motivation:
    """A base for a motivation in Python (duck typing works as well).

    decide(percept) gets a dict: step; affordance and learning_progress
    (numpy arrays of the 4 actions); with needs_memory, look (which look the
    focused object is, -1 without) and tried_ago (steps since each action was
    tried on it, -1: never); with needs_last_change, last_change (|change|
    the previous step's action caused). It returns a Decision (or a dict or
    an object with act, action, motivation, threshold).
    """

    kind: str = ""                # motivation.kind naming it (default: the class name in lower case)
    needs_memory: bool = False
    needs_last_change: bool = False

    def __init__(self, config: dict[str, Any]):
        self.config = config

    def decide(self, percept: dict[str, Any]) -> Decision:
        raise NotImplementedError


class AffordancePredictor:
    """A base for an affordance predictor in Python (duck typing works as well).

    The predictors process keeps the forward models, the memory and replay;
    this part predicts and learns the affordances (and the learning
    progress, IMP's signal). Images are focus images, side x side x 3 uint8
    (config["eye"]["focus_side"]); actions are 0..3 (ACTIONS).

    predict(image) -> (affordance, learning_progress), 4 numbers each: the
    predicted success of each action, and its learning progress.
    learn(image, action, succeeded) -> (before, after, learning_progress): the
    action's affordance output before and after this update, and its
    learning-progress output before its own update.
    relearn(image, action, succeeded): replay (predictors.replay) learns the
    affordance again from a remembered experience.
    state(action) -> a list of float64 numpy arrays (contiguous, writeable):
    together over the actions, the whole state. The weights checksum hashes
    them, a checkpoint saves them, and loading one writes into them in place.
    """

    kind: str = ""                # predictors.affordance.kind naming it (default: the class name in lower case)

    def __init__(self, config: dict[str, Any]):
        self.config = config

    def predict(self, image):
        raise NotImplementedError

    def learn(self, image, action: int, succeeded: bool):
        raise NotImplementedError

    def relearn(self, image, action: int, succeeded: bool) -> None:
        raise NotImplementedError(f"{type(self).__name__} does not replay (predictors.replay.enabled)")

    def state(self, action: int) -> list:
        raise NotImplementedError


GOAL_MODULES = ("explore", "colour", "move", "colour_place")  # goal_t's module ids 0..3


@dataclass
class Goal:
    module: str                   # one of GOAL_MODULES
    object_x: float = -1.0        # the object to act on, where it was seen (not for explore)
    object_y: float = -1.0
    x: float = -1.0               # the goal place
    y: float = -1.0
    image: Any = None             # the focus image wanted at (x, y): side x side x 3 uint8
    action: int = -1              # explore: the action to try (0..3)


class GoalChooser:
    """A base for a goal chooser in Python (goals.kind; the goals phase, system GOALS).

    next(step, id) returns the goal the planner pursues next (an afford.Goal,
    or a dict or an object with its fields). The others, called before it with
    everything published before the last goal ended, are optional:
    saw_object(step, image, x, y): an object the eye showed;
    saw_effect(effect): a dict with step, action, before_image, before (x, y),
    after_image, after (x, y), target (x, y) and affordance (the effect held);
    imagined(outcome): a dict with step, action, object_image, image and place:
    what the forward models predict the action does to that object;
    attempted(attempt): a dict with id, module, reached, distance, actions.
    Images are side x side x 3 uint8 (config["eye"]["focus_side"]).
    """

    kind: str = ""                # goals.kind naming it (default: the class name in lower case)

    def __init__(self, config: dict[str, Any]):
        self.config = config

    def next(self, step: int, id: int) -> Goal:
        raise NotImplementedError


class KeyedRng:
    """The run's keyed generator for a component: the draws of (seed, step, sub), whenever made.

    The C++ generator itself (KeyedRng(seed, step, Purpose::Component, sub)), so
    a component draws the same in Python as in C++. `purpose` other than
    "component" gives the draws of a shipped component, to port it exactly:
    "learning_progress_init" (sub: the action; the i-th draw's lowest bit is
    the sign of weight i), "replay", "revisit".
    """

    def __init__(self, seed: int, step: int, sub: int, purpose: str = "component"):
        self._rng = _afford.KeyedRng(seed, step, sub, purpose)

    def bits(self, i: int = 0) -> int:
        return self._rng.bits(i)

    def uniform(self, i: int = 0) -> float:
        return self._rng.uniform(i)

    def integer(self, n: int, i: int = 0) -> int:
        """In [0, n), from the i-th draw."""
        return self.bits(i) % n


_NAME = re.compile(r"^[a-z0-9_-]{1,64}$")


def kind_of(cls: Any) -> str:
    kind = getattr(cls, "kind", "") or cls.__name__.lower()
    if not _NAME.match(kind):
        raise ValueError(f"component kind {kind!r} of {cls!r}: use lower-case letters, digits, '_' or '-' "
                         "(set the class attribute `kind`)")
    return kind


def register_motivation(cls: Any, kind: str | None = None) -> str:
    """Make `cls` the motivation of motivation.kind `kind` (default: kind_of(cls)) in this process."""
    kind = kind or kind_of(cls)
    if not _NAME.match(kind):
        raise ValueError(f"motivation kind {kind!r}: use lower-case letters, digits, '_' or '-'")
    if not callable(getattr(cls, "decide", None)):
        raise TypeError(f"{cls!r} has no decide(percept)")
    _afford.register_motivation(kind, cls)
    return kind


def register_affordance(cls: Any, kind: str | None = None) -> str:
    """Make `cls` the affordance predictor of predictors.affordance.kind `kind` (default: kind_of(cls)) here."""
    kind = kind or kind_of(cls)
    if not _NAME.match(kind):
        raise ValueError(f"affordance predictor kind {kind!r}: use lower-case letters, digits, '_' or '-'")
    for method in ("predict", "learn", "state"):
        if not callable(getattr(cls, method, None)):
            raise TypeError(f"{cls!r} has no {method}() (an affordance predictor has predict, learn, relearn, state)")
    _afford.register_affordance(kind, cls)
    return kind


def register_goals(cls: Any, kind: str | None = None) -> str:
    """Make `cls` the goal chooser of goals.kind `kind` (default: kind_of(cls)) in this process."""
    kind = kind or kind_of(cls)
    if not _NAME.match(kind):
        raise ValueError(f"goal chooser kind {kind!r}: use lower-case letters, digits, '_' or '-'")
    if not callable(getattr(cls, "next", None)):
        raise TypeError(f"{cls!r} has no next(step, id)")
    _afford.register_goals(kind, cls)
    return kind


# What a process written in Python can stand in for, with the config key of its kind and how to register it.
# (A goal chooser is the motivation process's in the goals phase: `afford.process goals` is that process.)
ROLES = {
    "motivation": ("motivation.kind", register_motivation),
    "predictors": ("predictors.affordance.kind", register_affordance),
    "goals": ("goals.kind", register_goals),
}
